#pragma once

// Little-endian encoding of fixed-width fields for the map file formats (map_file_header.h,
// submap_file.h, map_manifest.h): every field is written byte by byte, never as a memcpy of a
// struct, and every read is bounded by the bytes that remain. Internal to cblox_persistence
// (and its tests, which forge hostile files with it).

#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace cblox::persistence_detail {

/// Appends little-endian fields to a byte string. Not thread-safe (one writer per object).
class ByteWriter {
 public:
  /// Writes into *out (non-null, not owned), appending to what it holds.
  explicit ByteWriter(std::string* out) : out_(out) {}

  void u8(uint8_t v) { out_->push_back(static_cast<char>(v)); }
  void u32(uint32_t v) { appendLe(v, 4); }
  void u64(uint64_t v) { appendLe(v, 8); }
  void i32(int32_t v) { u32(static_cast<uint32_t>(v)); }
  void i64(int64_t v) { u64(static_cast<uint64_t>(v)); }
  /// IEEE-754 bits, so every float (NaN payloads included) reads back bit-identical.
  void f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
  /// Raw bytes, no length.
  void bytes(std::string_view b) { out_->append(b.data(), b.size()); }
  /// LEB128: 7 bits per byte, least significant first, high bit = more follow (1-10 bytes).
  void uvarint(uint64_t v) {
    while (v >= 0x80) {
      u8(static_cast<uint8_t>(v | 0x80));
      v >>= 7;
    }
    u8(static_cast<uint8_t>(v));
  }
  /// uint32 length, then the bytes. Precondition: s.size() < 2^32.
  void str(std::string_view s) {
    u32(static_cast<uint32_t>(s.size()));
    bytes(s);
  }

 private:
  void appendLe(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out_->push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
  }
  std::string* out_;
};

/// Reads little-endian fields from a byte range. A read past the end fails: it returns false,
/// leaves the output unchanged and the reader stays failed (ok() == false), so a caller may
/// read a whole record and test ok() once. Not thread-safe (one reader per object); the bytes
/// must outlive it.
class ByteReader {
 public:
  explicit ByteReader(std::string_view data) : data_(data) {}

  /// False once a read went past the end.
  bool ok() const { return ok_; }
  /// Bytes not read yet.
  size_t remaining() const { return data_.size() - pos_; }
  /// Offset of the next byte.
  size_t position() const { return pos_; }

  bool u8(uint8_t* v) {
    uint64_t x = 0;
    if (!readLe(&x, 1)) return false;
    *v = static_cast<uint8_t>(x);
    return true;
  }
  bool u32(uint32_t* v) {
    uint64_t x = 0;
    if (!readLe(&x, 4)) return false;
    *v = static_cast<uint32_t>(x);
    return true;
  }
  bool u64(uint64_t* v) { return readLe(v, 8); }
  bool i32(int32_t* v) {
    uint32_t x = 0;
    if (!u32(&x)) return false;
    *v = static_cast<int32_t>(x);
    return true;
  }
  bool i64(int64_t* v) {
    uint64_t x = 0;
    if (!u64(&x)) return false;
    *v = static_cast<int64_t>(x);
    return true;
  }
  bool f32(float* v) {
    uint32_t x = 0;
    if (!u32(&x)) return false;
    *v = std::bit_cast<float>(x);
    return true;
  }
  bool f64(double* v) {
    uint64_t x = 0;
    if (!u64(&x)) return false;
    *v = std::bit_cast<double>(x);
    return true;
  }
  /// A uvarint (ByteWriter::uvarint); fails at the end of the data, after 10 bytes, or when
  /// the value does not fit 64 bits.
  bool uvarint(uint64_t* v) {
    uint64_t x = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      uint8_t byte = 0;
      if (!u8(&byte)) return false;
      const uint64_t bits = byte & 0x7fu;
      if (shift == 63 && bits > 1) return ok_ = false;
      x |= bits << shift;
      if ((byte & 0x80u) == 0) {
        *v = x;
        return true;
      }
    }
    return ok_ = false;
  }
  /// The next n bytes as a view into the data (no copy); fails when fewer remain.
  bool bytes(size_t n, std::string_view* v) {
    if (!ok_ || n > remaining()) return ok_ = false;
    *v = data_.substr(pos_, n);
    pos_ += n;
    return true;
  }
  /// A uint32 length, then that many bytes; fails when the length exceeds `max_length` or the
  /// bytes that remain (checked before anything is allocated).
  bool str(std::string* s, size_t max_length) {
    uint32_t n = 0;
    if (!u32(&n)) return false;
    if (n > max_length) return ok_ = false;
    std::string_view view;
    if (!bytes(n, &view)) return false;
    s->assign(view);
    return true;
  }

 private:
  bool readLe(uint64_t* v, size_t n) {
    if (!ok_ || n > remaining()) return ok_ = false;
    uint64_t x = 0;
    for (size_t i = 0; i < n; ++i) {
      x |= static_cast<uint64_t>(static_cast<unsigned char>(data_[pos_ + i])) << (8 * i);
    }
    pos_ += n;
    *v = x;
    return true;
  }

  std::string_view data_;
  size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace cblox::persistence_detail
