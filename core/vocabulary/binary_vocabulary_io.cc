// File format of a BinaryVocabulary, version 1 (all integers little-endian):
//
//   offset  size  field
//   0       8     magic "CBLXVOCB"
//   8       4     uint32 format version (1)
//   12      4     uint32 k (branching)
//   16      4     uint32 L (levels)
//   20      4     uint32 node count n (root included)
//   24      4     uint32 word count w (leaves)
//   28      8     uint64 number of training images
//   36      4     uint32 description length d (<= 65536)
//   40      d     description (UTF-8, e.g. where the training images came from)
//   ...     36 (n - 1)  nodes 1 .. n-1: uint32 parent, 32-byte descriptor (OrbDescriptor bytes)
//   ...     8 w   float64 idf weight of each word (words = leaves in node-id order)
//   ...     8     uint64 FNV-1a 64-bit hash of every byte before it
//
// The root (node 0) is implicit. Children of a node are a contiguous id range after it.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/vocabulary/binary_vocabulary.h"

namespace cblox {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the vocabulary file format is little-endian");

constexpr char kMagic[8] = {'C', 'B', 'L', 'X', 'V', 'O', 'C', 'B'};
constexpr uint32_t kFormatVersion = 1;
constexpr size_t kHeaderBytes = 40;
constexpr size_t kNodeBytes = 4 + 32;
constexpr uint32_t kMaxDescriptionBytes = 65536;

uint64_t fnv1a(std::string_view bytes) {
  uint64_t hash = 0xcbf29ce484222325ull;
  for (const char c : bytes) {
    hash ^= static_cast<uint8_t>(c);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

template <typename T>
void put(std::string* out, const T& value) {
  out->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T get(std::string_view bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

std::string hex(uint64_t value) {
  std::ostringstream s;
  s << "0x" << std::hex << value;
  return s.str();
}

bool fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

}  // namespace

std::string BinaryVocabulary::serialize() const {
  std::string out;
  out.reserve(kHeaderBytes + description_.size() + nodeCount() * kNodeBytes + wordCount() * 8 + 8);
  out.append(kMagic, sizeof(kMagic));
  put(&out, kFormatVersion);
  put(&out, static_cast<uint32_t>(branching_));
  put(&out, static_cast<uint32_t>(levels_));
  put(&out, static_cast<uint32_t>(nodeCount()));
  put(&out, static_cast<uint32_t>(wordCount()));
  put(&out, training_images_);
  put(&out, static_cast<uint32_t>(description_.size()));
  out += description_;
  for (size_t i = 1; i < nodeCount(); ++i) {
    put(&out, node_parent_[i]);
    char bytes[32];
    node_descriptor_[i].toBytes(reinterpret_cast<uint8_t*>(bytes));
    out.append(bytes, 32);
  }
  for (const double weight : word_weight_) put(&out, weight);
  put(&out, fnv1a(out));
  return out;
}

std::optional<BinaryVocabulary> BinaryVocabulary::deserialize(std::string_view bytes,
                                                              std::string* error) {
  const size_t size = bytes.size();
  const size_t magic_bytes = std::min(size, sizeof(kMagic));
  if (std::memcmp(bytes.data(), kMagic, magic_bytes) != 0) {
    fail(error,
         "wrong magic: not a cblox vocabulary file (expected it to start with \"CBLXVOCB\")");
    return std::nullopt;
  }
  if (size < kHeaderBytes) {
    fail(error, "truncated file: " + std::to_string(size) + " bytes, shorter than the " +
                    std::to_string(kHeaderBytes) + "-byte header");
    return std::nullopt;
  }
  const auto version = get<uint32_t>(bytes, 8);
  if (version != kFormatVersion) {
    fail(error, "unsupported format version " + std::to_string(version) + " (this build reads " +
                    std::to_string(kFormatVersion) + ")");
    return std::nullopt;
  }
  const auto k = get<uint32_t>(bytes, 12), levels = get<uint32_t>(bytes, 16);
  const auto nodes = get<uint32_t>(bytes, 20), words = get<uint32_t>(bytes, 24);
  const auto description_bytes = get<uint32_t>(bytes, 36);
  if (k < 2 || k > 64 || levels < 1 || levels > 8 || nodes < 2 || words < 1 || words >= nodes ||
      description_bytes > kMaxDescriptionBytes) {
    fail(error, "corrupt header: k = " + std::to_string(k) + ", L = " + std::to_string(levels) +
                    ", " + std::to_string(nodes) + " nodes, " + std::to_string(words) +
                    " words, description of " + std::to_string(description_bytes) + " bytes");
    return std::nullopt;
  }
  const size_t nodes_at = kHeaderBytes + description_bytes;
  const size_t weights_at = nodes_at + (static_cast<size_t>(nodes) - 1) * kNodeBytes;
  const size_t checksum_at = weights_at + static_cast<size_t>(words) * 8;
  const size_t expected = checksum_at + 8;
  if (size < expected) {
    fail(error, "truncated file: the header announces " + std::to_string(expected) +
                    " bytes, the file has " + std::to_string(size));
    return std::nullopt;
  }
  if (size > expected) {
    fail(error, "corrupt file: " + std::to_string(size - expected) +
                    " bytes after the end the header announces (" + std::to_string(expected) +
                    " bytes)");
    return std::nullopt;
  }
  const auto stored = get<uint64_t>(bytes, checksum_at);
  const uint64_t computed = fnv1a(bytes.substr(0, checksum_at));
  if (stored != computed) {
    fail(error, "checksum mismatch (stored " + hex(stored) + ", computed " + hex(computed) +
                    "): the file is corrupt");
    return std::nullopt;
  }
  BinaryVocabulary v;
  v.branching_ = static_cast<int>(k);
  v.levels_ = static_cast<int>(levels);
  v.training_images_ = get<uint64_t>(bytes, 28);
  v.description_ = std::string(bytes.substr(kHeaderBytes, description_bytes));
  v.node_parent_.assign(nodes, kNoParent);
  v.node_descriptor_.assign(nodes, OrbDescriptor{});
  for (size_t i = 1; i < nodes; ++i) {
    const size_t at = nodes_at + (i - 1) * kNodeBytes;
    v.node_parent_[i] = get<uint32_t>(bytes, at);
    v.node_descriptor_[i] =
        OrbDescriptor::fromBytes(reinterpret_cast<const uint8_t*>(bytes.data() + at + 4));
  }
  if (const std::string problem = v.buildTopology(); !problem.empty()) {
    fail(error, "inconsistent tree: " + problem);
    return std::nullopt;
  }
  if (v.wordCount() != words) {
    fail(error, "inconsistent tree: the header announces " + std::to_string(words) +
                    " words, the tree has " + std::to_string(v.wordCount()) + " leaves");
    return std::nullopt;
  }
  v.word_weight_.resize(words);
  for (size_t w = 0; w < words; ++w) {
    v.word_weight_[w] = get<double>(bytes, weights_at + 8 * w);
    if (!(v.word_weight_[w] >= 0.0) || !std::isfinite(v.word_weight_[w])) {
      fail(error, "corrupt weight of word " + std::to_string(w));
      return std::nullopt;
    }
  }
  return v;
}

bool BinaryVocabulary::save(const std::string& path, std::string* error) const {
  // Write a sibling file and rename it, so readers never see a half-written vocabulary.
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    const std::string bytes = serialize();
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) return fail(error, path + ": cannot write " + temporary);
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) return fail(error, path + ": cannot rename " + temporary + ": " + ec.message());
  return true;
}

std::optional<BinaryVocabulary> BinaryVocabulary::load(const std::string& path,
                                                       std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    fail(error, path + ": cannot open");
    return std::nullopt;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) {
    fail(error, path + ": read error");
    return std::nullopt;
  }
  std::string message;
  std::optional<BinaryVocabulary> v = deserialize(buffer.str(), &message);
  if (!v.has_value()) fail(error, path + ": " + message);
  return v;
}

}  // namespace cblox
