#include "lcmtypes/wire_check.h"

#include <algorithm>
#include <array>
#include <cinttypes>
#include <cstdio>
#include <limits>
#include <utility>

#include <cblox/wire_schema.hpp>

namespace cblox {

namespace {

namespace ws = wire_schema;

constexpr uint64_t kSaturated = std::numeric_limits<uint64_t>::max();

// a * b, saturating at kSaturated.
uint64_t satMul(uint64_t a, uint64_t b) {
  return b != 0 && a > kSaturated / b ? kSaturated : a * b;
}

// Minimum encoded bytes of one element of dimension `level` of field f: the product of the
// dimensions below it times the element's minimum size (saturating). `counts` holds f's
// dimensions.
uint64_t minElementSize(const ws::Field& f, const uint64_t* counts, int level) {
  uint64_t size = static_cast<uint64_t>(f.elem_min_size);
  for (int d = level + 1; d < f.num_dims; ++d) size = satMul(size, counts[d]);
  return size;
}

const ws::Struct* findStruct(std::string_view name) {
  if (name.size() > ws::kPackage.size() && name.substr(0, ws::kPackage.size()) == ws::kPackage &&
      name[ws::kPackage.size()] == '.') {
    name.remove_prefix(ws::kPackage.size() + 1);
  }
  for (const ws::Struct& s : ws::kStructs) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

// One walk over one message (not shared between threads). On failure the walk functions
// return false with error_, path_ (the member, e.g. "pairs[1].error") and message_ set.
class Walker {
 public:
  Walker(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  size_t pos() const { return pos_; }
  WireCheck failure() const {
    return {error_, "field " + path_ + ": " + message_};
  }

  // Walks the members of s (no fingerprint). Recursion depth is bounded by the number of
  // structs: lcm_schema.py rejects recursive types.
  bool walkStruct(const ws::Struct& s) {
    const ws::Field* fields = ws::kFields.data() + s.first_field;
    std::array<int64_t, ws::kMaxFields> values{};  // scalar integer members, by index
    for (int i = 0; i < s.num_fields; ++i) {
      if (!walkField(fields, i, values.data())) return false;
    }
    return true;
  }

 private:
  size_t left() const { return size_ - pos_; }

  bool fail(WireError error, const ws::Field& f, std::string message) {
    error_ = error;
    path_ = std::string(f.name);
    message_ = std::move(message);
    return false;
  }

  // Checks that n more bytes are there.
  bool need(const ws::Field& f, uint64_t n) {
    if (n <= left()) return true;
    return fail(WireError::kTruncated, f,
                "needs " + std::to_string(n) + " bytes, " + std::to_string(left()) + " left");
  }

  // Reads a big-endian signed integer of `bytes` (1, 2, 4 or 8) bytes; need() first.
  int64_t readSigned(int bytes) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = v << 8 | data_[pos_ + static_cast<size_t>(i)];
    pos_ += static_cast<size_t>(bytes);
    const int unused = 64 - 8 * bytes;  // sign-extend
    return unused == 0 ? static_cast<int64_t>(v)
                       : static_cast<int64_t>(v << unused) >> unused;  // arithmetic shift
  }

  // Walks member `index` of the struct whose members start at `fields`; `values` holds the
  // struct's scalar integer members read so far (the array counts).
  bool walkField(const ws::Field* fields, int index, int64_t* values) {
    const ws::Field& f = fields[index];
    const bool fixed_size = f.kind != ws::Kind::kString && f.kind != ws::Kind::kStruct;
    if (f.num_dims == 0 && fixed_size) {  // scalar: the common case
      const int bytes = static_cast<int>(f.elem_min_size);
      if (!need(f, static_cast<uint64_t>(bytes))) return false;
      values[index] = readSigned(bytes);  // meaningful for integers only; others unused
      return true;
    }

    // Every count first, then bound each variable one: count x (minimum size of one element
    // of that dimension, at least 1 so zero-size elements cannot multiply) <= bytes left.
    std::array<uint64_t, ws::kMaxDims> counts{};
    uint64_t total = 1;
    for (int d = 0; d < f.num_dims; ++d) {
      const ws::Dim& dim = ws::kDims[static_cast<size_t>(f.first_dim + d)];
      const int64_t n = dim.field < 0 ? dim.size : values[dim.field];
      if (n < 0) {
        return fail(WireError::kLengthOutOfBounds, f,
                    "length " + std::to_string(n) + " (" + std::string(fields[dim.field].name) +
                        ") is negative");
      }
      counts[static_cast<size_t>(d)] = static_cast<uint64_t>(n);
      total = satMul(total, static_cast<uint64_t>(n));
    }
    for (int d = 0; d < f.num_dims; ++d) {
      const ws::Dim& dim = ws::kDims[static_cast<size_t>(f.first_dim + d)];
      if (dim.field < 0) continue;  // a literal: the schema bounds it
      const uint64_t element = std::max<uint64_t>(1, minElementSize(f, counts.data(), d));
      if (satMul(counts[static_cast<size_t>(d)], element) > left()) {
        return fail(WireError::kLengthOutOfBounds, f,
                    "length " + std::to_string(counts[static_cast<size_t>(d)]) + " (" +
                        std::string(fields[dim.field].name) + ") x " +
                        std::to_string(element) + " bytes exceeds the " +
                        std::to_string(left()) + " bytes left");
      }
    }

    if (fixed_size) {  // primitive array: one block
      if (!need(f, satMul(total, static_cast<uint64_t>(f.elem_min_size)))) return false;
      pos_ += static_cast<size_t>(total * static_cast<uint64_t>(f.elem_min_size));
      return true;
    }
    // `total` is bounded here: by the bytes left (each element costs >= 1) times the literal
    // dimensions.
    for (uint64_t i = 0; i < total; ++i) {
      if (f.kind == ws::Kind::kString ? !walkString(f)
                                      : !walkStruct(ws::kStructs[static_cast<size_t>(
                                            f.struct_index)])) {
        // Name the element: "name[i]" (i flat over all dimensions), then the nested path.
        std::string element(f.name);
        if (f.num_dims > 0) element.append("[").append(std::to_string(i)).append("]");
        if (f.kind == ws::Kind::kStruct) element.append(".").append(path_);
        path_ = std::move(element);
        return false;
      }
    }
    return true;
  }

  bool walkString(const ws::Field& f) {
    if (!need(f, 4)) return false;
    const int64_t length = readSigned(4);
    if (length < 1) {
      return fail(WireError::kLengthOutOfBounds, f,
                  "string length " + std::to_string(length) + " is below 1 (it counts the NUL)");
    }
    if (static_cast<uint64_t>(length) > left()) {
      return fail(WireError::kLengthOutOfBounds, f,
                  "string length " + std::to_string(length) + " exceeds the " +
                      std::to_string(left()) + " bytes left");
    }
    pos_ += static_cast<size_t>(length);
    return true;
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  WireError error_ = WireError::kNone;
  std::string path_, message_;
};

std::string hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "0x%016" PRIx64, v);
  return buf;
}

}  // namespace

const char* wireErrorName(WireError error) {
  switch (error) {
    case WireError::kNone: return "none";
    case WireError::kTooShort: return "too_short";
    case WireError::kFingerprintMismatch: return "fingerprint_mismatch";
    case WireError::kLengthOutOfBounds: return "length_out_of_bounds";
    case WireError::kTruncated: return "truncated";
    case WireError::kTrailingBytes: return "trailing_bytes";
    case WireError::kDecodeFailed: return "decode_failed";
    case WireError::kCount: break;
  }
  return "invalid";
}

WireCheck checkWire(const void* data, size_t size, std::string_view type_name,
                    int64_t expected_hash) noexcept {
  try {
    const ws::Struct* type = findStruct(type_name);
    if (type == nullptr) {
      return {WireError::kDecodeFailed,
              "type " + std::string(type_name) + " is not in the wire schema"};
    }
    if (size < 8) {
      return {WireError::kTooShort, "message of " + std::to_string(size) +
                                        " bytes has no 8-byte fingerprint"};
    }
    const auto* bytes = static_cast<const uint8_t*>(data);
    uint64_t hash = 0;
    for (size_t i = 0; i < 8; ++i) hash = hash << 8 | bytes[i];
    if (hash != static_cast<uint64_t>(expected_hash)) {
      return {WireError::kFingerprintMismatch,
              "fingerprint " + hex(hash) + " is not " + std::string(type->name) + "'s " +
                  hex(static_cast<uint64_t>(expected_hash))};
    }
    Walker walker(bytes + 8, size - 8);
    if (!walker.walkStruct(*type)) return walker.failure();
    if (walker.pos() != size - 8) {
      return {WireError::kTrailingBytes, "the encoding ends after " +
                                             std::to_string(walker.pos() + 8) + " of the " +
                                             std::to_string(size) + " bytes"};
    }
    return {};
  } catch (...) {  // std::bad_alloc building a detail
    return {WireError::kDecodeFailed, {}};
  }
}

namespace wire_check_internal {

WireCheck decodeFailure(int read, size_t size, const char* what) noexcept {
  WireCheck check{WireError::kDecodeFailed, {}};
  try {
    if (size > static_cast<size_t>(INT_MAX)) {
      check.detail = "message of " + std::to_string(size) + " bytes exceeds LCM's 2^31 - 1";
    } else if (what != nullptr) {
      check.detail = std::string("decode threw: ") + what;
    } else {
      check.detail = "decode returned " + std::to_string(read) + " for " + std::to_string(size) +
                     " bytes that passed the wire check";
    }
  } catch (...) {  // std::bad_alloc: leave the detail empty
  }
  return check;
}

}  // namespace wire_check_internal

}  // namespace cblox
