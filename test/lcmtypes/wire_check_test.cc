// Tests of lcmtypes/wire_check.h (checkWire, decodeChecked) over every cblox LCM type.
//
// The types come from CBLOX_WIRE_SCHEMA_FOR_EACH_TYPE (generated from lcmtypes/*.lcm), so a
// new .lcm file does not compile here until it has a filled() builder below. For every type:
// valid messages pass and round-trip; every 4-byte overwrite, byte flip and truncation of
// their encodings is refused or accepted without throwing, without decode() disagreeing
// with the walk, and without any single allocation larger than the message plus
// kAllocationSlack. The allocation sizes are measured by replacing the global operator
// new/new[] in this binary (the one global: g_allocations). Specific corruptions give
// specific errors, and the unchecked generated decode() is shown to throw / over-allocate
// on them (the defect the check guards against).

#include <gtest/gtest.h>
#include <cblox/camera_calibration_t.hpp>
#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/covariance_pair_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/distance_reply_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/local_grid_t.hpp>
#include <cblox/mesh_block_t.hpp>
#include <cblox/mesh_update_t.hpp>
#include <cblox/subvolume_list_t.hpp>
#include <cblox/depth_frame_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/image_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/map_status_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/pose_t.hpp>
#include <cblox/stereo_pair_t.hpp>
#include <cblox/wire_schema.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <new>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "lcmtypes/wire_check.h"
#include "test/test_support/lcm_samples.h"

// ---------------------------------------------------------------------------------------
// Allocation counter. While `counting` is set, every operator new/new[] of this binary
// records the largest single request and refuses (std::bad_alloc) requests over
// kRefuseAbove, so a regression fails a test instead of exhausting the machine's memory.
// Counting is for one thread at a time (CountAllocations below).

namespace {

struct AllocationCounter {
  std::atomic<bool> counting{false};
  std::atomic<size_t> largest{0};
};
AllocationCounter g_allocations;

constexpr size_t kRefuseAbove = size_t{64} << 20;

void* countedAllocate(size_t size) {
  if (g_allocations.counting.load(std::memory_order_relaxed)) {
    size_t largest = g_allocations.largest.load(std::memory_order_relaxed);
    while (size > largest && !g_allocations.largest.compare_exchange_weak(largest, size)) {
    }
    if (size > kRefuseAbove) throw std::bad_alloc();
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t size) { return countedAllocate(size); }
void* operator new[](std::size_t size) { return countedAllocate(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {

using cblox::WireCheck;
using cblox::WireError;
using Bytes = std::vector<uint8_t>;

// Any single allocation of decodeChecked() on a message of n bytes is at most
// n + kAllocationSlack (the slack covers the failure detail string and the in-memory size of
// small structs exceeding their encoding).
constexpr size_t kAllocationSlack = 256;

// Counts the largest allocation of the calling thread's scope (not reentrant).
class CountAllocations {
 public:
  CountAllocations() {
    g_allocations.largest = 0;
    g_allocations.counting = true;
  }
  ~CountAllocations() { g_allocations.counting = false; }
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
  size_t largest() const { return g_allocations.largest; }
};

template <typename T>
Bytes encode(const T& msg) {
  Bytes buf(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(buf.data(), 0, static_cast<int>(buf.size())),
            static_cast<int>(buf.size()));
  return buf;
}

// Overwrites up to 4 bytes at `offset` with `value`, big-endian, clipped at the end.
void put32(Bytes* bytes, size_t offset, uint32_t value) {
  for (size_t i = 0; i < 4 && offset + i < bytes->size(); ++i) {
    (*bytes)[offset + i] = static_cast<uint8_t>(value >> (24 - 8 * i));
  }
}

// ---------------------------------------------------------------------------------------
// filled(Tag<T>): a message of type T with distinctive values, strings and non-empty arrays,
// from the shared builders of test/test_support/lcm_samples.h.

template <typename T>
struct Tag {};

namespace samples = cblox::test;

cblox::pose_t filled(Tag<cblox::pose_t>) { return samples::MakePose(0.25); }
cblox::image_t filled(Tag<cblox::image_t>) {
  return samples::MakeImage("cam0", cblox::image_t::RGB8, 5, 3, 3, 1);
}
cblox::camera_calibration_t filled(Tag<cblox::camera_calibration_t>) {
  return samples::MakeCalibration("cam0", 0.0);
}
cblox::stereo_pair_t filled(Tag<cblox::stereo_pair_t>) { return samples::MakeStereoPair(); }
cblox::depth_frame_t filled(Tag<cblox::depth_frame_t>) { return samples::MakeDepthFrame(); }
cblox::pose_stamped_t filled(Tag<cblox::pose_stamped_t>) { return samples::MakePoseStamped(); }
cblox::frame_pose_t filled(Tag<cblox::frame_pose_t>) { return samples::MakeFramePose(); }
cblox::keyframe_t filled(Tag<cblox::keyframe_t>) { return samples::MakeKeyframe(); }
cblox::keyframe_pose_batch_t filled(Tag<cblox::keyframe_pose_batch_t>) {
  return samples::MakeKeyframePoseBatch();
}
cblox::covariance_request_t filled(Tag<cblox::covariance_request_t>) {
  return samples::MakeCovarianceRequest();
}
cblox::covariance_pair_t filled(Tag<cblox::covariance_pair_t>) {
  return samples::MakeCovariancePair(12, 40, true);
}
cblox::covariance_reply_t filled(Tag<cblox::covariance_reply_t>) {
  return samples::MakeCovarianceReply();
}
cblox::command_t filled(Tag<cblox::command_t>) { return samples::MakeCommand(); }
cblox::command_reply_t filled(Tag<cblox::command_reply_t>) { return samples::MakeCommandReply(); }
cblox::map_status_t filled(Tag<cblox::map_status_t>) { return samples::MakeMapStatus(); }
cblox::heartbeat_t filled(Tag<cblox::heartbeat_t>) { return samples::MakeHeartbeat(); }
cblox::distance_request_t filled(Tag<cblox::distance_request_t>) {
  return samples::MakeDistanceRequest();
}
cblox::distance_reply_t filled(Tag<cblox::distance_reply_t>) {
  return samples::MakeDistanceReply();
}
cblox::local_grid_t filled(Tag<cblox::local_grid_t>) { return samples::MakeLocalGrid(); }
cblox::mesh_block_t filled(Tag<cblox::mesh_block_t>) { return samples::MakeMeshBlock(1); }
cblox::mesh_update_t filled(Tag<cblox::mesh_update_t>) { return samples::MakeMeshUpdate(); }
cblox::subvolume_list_t filled(Tag<cblox::subvolume_list_t>) {
  return samples::MakeSubvolumeList();
}

// ---------------------------------------------------------------------------------------
// One case per schema type.

struct Outcome {
  WireCheck check;
  size_t largest_allocation = 0;  // of decodeChecked()
  Bytes reencoded;                // if asked for and the check passed
};

struct TypeCase {
  std::string name;    // T::getTypeName()
  int64_t hash = 0;    // T::getHash()
  Bytes filled;        // encoding of filled(Tag<T>)
  Bytes empty;         // encoding of a value-initialised T: empty strings and arrays
  // decodeChecked() as T with the allocation counter on; re-encodes the result if asked.
  std::function<Outcome(const uint8_t* data, size_t size, bool reencode)> decode;
  // The unchecked generated T::decode(); may throw.
  std::function<int(const Bytes&)> unchecked_decode;
};

template <typename T>
TypeCase makeCase() {
  TypeCase c;
  c.name = T::getTypeName();
  c.hash = T::getHash();
  c.filled = encode(filled(Tag<T>{}));
  c.empty = encode(T{});
  c.decode = [](const uint8_t* data, size_t size, bool reencode) {
    Outcome out;
    T msg{};
    {
      CountAllocations counting;
      out.check = cblox::decodeChecked(data, size, &msg);
      out.largest_allocation = counting.largest();
    }
    if (reencode && out.check.ok()) out.reencoded = encode(msg);
    return out;
  };
  c.unchecked_decode = [](const Bytes& bytes) {
    T msg{};
    return msg.decode(bytes.data(), 0, static_cast<int>(bytes.size()));
  };
  return c;
}

// Every type of the schema, in its (sorted) order. A type without a filled() overload or
// without its #include above does not compile.
std::vector<TypeCase> allCases() {
#define CBLOX_WIRE_TEST_CASE(TYPE) makeCase<cblox::TYPE>(),
  return {CBLOX_WIRE_SCHEMA_FOR_EACH_TYPE(CBLOX_WIRE_TEST_CASE)};
#undef CBLOX_WIRE_TEST_CASE
}

const TypeCase& findCase(const std::vector<TypeCase>& cases, const std::string& name) {
  for (const TypeCase& c : cases) {
    if (c.name == name) return c;
  }
  throw std::invalid_argument("no case " + name);
}

WireCheck check(const TypeCase& c, const Bytes& bytes) {
  return cblox::checkWire(bytes.data(), bytes.size(), c.name, c.hash);
}

// ---------------------------------------------------------------------------------------
// Coverage and valid messages.

TEST(lcm_wire, TheCasesAreExactlyTheSchemaTypes) {
  namespace ws = cblox::wire_schema;
  const std::vector<TypeCase> cases = allCases();
  ASSERT_EQ(cases.size(), ws::kStructs.size());
  EXPECT_EQ(cases.size(), 22U);  // lcmtypes/*.lcm; update with the folder
  std::set<int64_t> hashes;
  for (size_t i = 0; i < cases.size(); ++i) {
    EXPECT_EQ(cases[i].name, ws::kStructs[i].name);
    hashes.insert(cases[i].hash);
    // A value-initialised message has empty strings (5 bytes) and empty variable arrays:
    // exactly the schema's minimum size. Cross-checks the schema against lcm-gen's code.
    EXPECT_EQ(cases[i].empty.size(), 8 + static_cast<size_t>(ws::kStructs[i].min_size))
        << cases[i].name;
  }
  EXPECT_EQ(hashes.size(), cases.size());
}

TEST(lcm_wire, ValidMessagesPassAndRoundTrip) {
  for (const TypeCase& c : allCases()) {
    for (const Bytes* valid : {&c.filled, &c.empty}) {
      const WireCheck checked = check(c, *valid);
      EXPECT_EQ(checked.error, WireError::kNone) << c.name << ": " << checked.detail;
      EXPECT_TRUE(checked.detail.empty());
      const Outcome out = c.decode(valid->data(), valid->size(), true);
      EXPECT_EQ(out.check.error, WireError::kNone) << c.name << ": " << out.check.detail;
      EXPECT_EQ(out.reencoded, *valid) << c.name;
      EXPECT_LE(out.largest_allocation, valid->size() + kAllocationSlack) << c.name;
      // At an odd address too: the walk reads bytes, never wider loads.
      Bytes shifted(valid->size() + 1);
      std::copy(valid->begin(), valid->end(), shifted.begin() + 1);
      EXPECT_EQ(c.decode(shifted.data() + 1, valid->size(), true).reencoded, *valid) << c.name;
    }
  }
}

TEST(lcm_wire, PackagePrefixedTypeNameIsAccepted) {
  const Bytes bytes = encode(filled(Tag<cblox::keyframe_t>{}));
  EXPECT_TRUE(cblox::checkWire(bytes.data(), bytes.size(), "cblox.keyframe_t",
                               cblox::keyframe_t::getHash())
                  .ok());
}

// ---------------------------------------------------------------------------------------
// Every mutation of every valid encoding.

// Calls f(mutated) for: every 4-byte window at offset >= 8 (clipped at the end) set to each
// of kPatterns, every byte (fingerprint included) xor 0x01, 0x80 and 0xFF, and every strict
// prefix.
constexpr std::array<uint32_t, 5> kPatterns = {0xFFFFFFFFU, 0x7FFFFFFFU, 0x80000000U,
                                               0x00000000U, 0x00010000U};
enum class Mutation { kOverwrite, kFlip, kTruncate };

void forEachMutation(const Bytes& valid, const std::function<void(Mutation, const Bytes&)>& f) {
  for (size_t offset = 8; offset < valid.size(); ++offset) {
    for (const uint32_t pattern : kPatterns) {
      Bytes m = valid;
      put32(&m, offset, pattern);
      if (m != valid) f(Mutation::kOverwrite, m);
    }
  }
  for (size_t offset = 0; offset < valid.size(); ++offset) {
    for (const uint8_t mask : {uint8_t{0x01}, uint8_t{0x80}, uint8_t{0xFF}}) {
      Bytes m = valid;
      m[offset] ^= mask;
      f(Mutation::kFlip, m);
    }
  }
  for (size_t length = 0; length < valid.size(); ++length) {
    f(Mutation::kTruncate, Bytes(valid.begin(), valid.begin() + static_cast<ptrdiff_t>(length)));
  }
}

// What a strict prefix of a valid encoding must give: it holds the same counts, so it always
// ends too early.
bool truncationError(size_t size, const WireCheck& check) {
  if (size < 8) return check.error == WireError::kTooShort;
  return check.error == WireError::kTruncated || check.error == WireError::kLengthOutOfBounds;
}

TEST(lcm_wire, EveryMutationIsRefusedOrDecodedWithinTheAllocationBound) {
  std::array<size_t, static_cast<size_t>(WireError::kCount)> by_error{};
  size_t inputs = 0, failures = 0;
  long worst_excess = -1'000'000;  // largest allocation - message size
  long worst_excess_accepted = -1'000'000;  // the same over the messages that passed
  // The unchecked generated decode() on the same inputs: throws, or allocates more than the
  // bound (requests over kRefuseAbove are refused: they throw std::bad_alloc).
  size_t unchecked_throws = 0, unchecked_over_allocates = 0;
  const auto start = std::chrono::steady_clock::now();
  for (const TypeCase& c : allCases()) {
    for (const Bytes* valid : {&c.filled, &c.empty}) {
      forEachMutation(*valid, [&](Mutation mutation, const Bytes& m) {
        ++inputs;
        const Outcome out = c.decode(m.data(), m.size(), false);  // noexcept: throw = abort
        ++by_error[static_cast<size_t>(out.check.error)];
        const long excess =
            static_cast<long>(out.largest_allocation) - static_cast<long>(m.size());
        worst_excess = std::max(worst_excess, excess);
        if (out.check.ok()) worst_excess_accepted = std::max(worst_excess_accepted, excess);
        try {
          CountAllocations counting;
          c.unchecked_decode(m);
          unchecked_over_allocates += counting.largest() > m.size() + kAllocationSlack;
        } catch (const std::exception&) {
          ++unchecked_throws;
        }
        std::string problem;
        if (out.largest_allocation > m.size() + kAllocationSlack) {
          problem = "allocated " + std::to_string(out.largest_allocation) + " bytes";
        } else if (out.check.error == WireError::kDecodeFailed) {
          problem = "decode disagrees with the walk: " + out.check.detail;  // never expected
        } else if (mutation == Mutation::kTruncate && !truncationError(m.size(), out.check)) {
          problem = std::string("a prefix gave ") + cblox::wireErrorName(out.check.error);
        } else if (!out.check.ok() && out.check.detail.empty()) {
          problem = "no detail";
        }
        if (!problem.empty() && ++failures <= 10) {
          ADD_FAILURE() << c.name << ", " << m.size() << " of " << valid->size()
                        << " bytes: " << problem;
        }
      });
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(failures, 0U);
  EXPECT_GT(inputs, 20'000U);
  // Every kind a walk can find occurs, and some mutations stay valid (e.g. a changed double).
  for (const WireError e : {WireError::kNone, WireError::kTooShort,
                            WireError::kFingerprintMismatch, WireError::kLengthOutOfBounds,
                            WireError::kTruncated, WireError::kTrailingBytes}) {
    EXPECT_GT(by_error[static_cast<size_t>(e)], 0U) << cblox::wireErrorName(e);
  }
  EXPECT_LE(worst_excess, static_cast<long>(kAllocationSlack));
  std::printf("[ figures  ] %zu mutated inputs (with unchecked decodes) in %.2f s; largest "
              "allocation <= size + %ld (size + %ld when accepted); unchecked decode() throws on %zu, allocates > size + %zu "
              "on %zu; decodeChecked():",
              inputs, seconds, worst_excess, worst_excess_accepted, unchecked_throws, kAllocationSlack,
              unchecked_over_allocates);
  for (size_t e = 0; e < by_error.size(); ++e) {
    std::printf(" %s %zu", cblox::wireErrorName(static_cast<WireError>(e)), by_error[e]);
  }
  std::printf("\n");
}

// ---------------------------------------------------------------------------------------
// Specific corruptions.

TEST(lcm_wire, NegativeCountIsLengthOutOfBoundsNamingTheField) {
  const cblox::keyframe_t msg = filled(Tag<cblox::keyframe_t>{});
  Bytes bytes = encode(msg);
  const size_t count_at = bytes.size() - 4 - 8 * msg.landmark_ids.size();  // num_landmarks
  put32(&bytes, count_at, 0xFFFFFFFFU);
  cblox::keyframe_t out;
  const WireCheck checked = cblox::decodeChecked(bytes.data(), bytes.size(), &out);
  EXPECT_EQ(checked.error, WireError::kLengthOutOfBounds);
  EXPECT_EQ(checked.detail, "field landmark_ids: length -1 (num_landmarks) is negative");

  put32(&bytes, count_at, 0x7FFFFFFFU);
  const WireCheck huge = cblox::decodeChecked(bytes.data(), bytes.size(), &out);
  EXPECT_EQ(huge.error, WireError::kLengthOutOfBounds);
  EXPECT_EQ(huge.detail,
            "field landmark_ids: length 2147483647 (num_landmarks) x 8 bytes exceeds the 32 "
            "bytes left");

  put32(&bytes, count_at, 5);  // one more than the 4 ids present
  EXPECT_EQ(cblox::decodeChecked(bytes.data(), bytes.size(), &out).error,
            WireError::kLengthOutOfBounds);
  put32(&bytes, count_at, 3);  // one id fewer: 8 bytes remain
  const WireCheck fewer = cblox::decodeChecked(bytes.data(), bytes.size(), &out);
  EXPECT_EQ(fewer.error, WireError::kTrailingBytes);
  EXPECT_EQ(fewer.detail, "the encoding ends after " + std::to_string(bytes.size() - 8) +
                              " of the " + std::to_string(bytes.size()) + " bytes");
}

TEST(lcm_wire, NegativeInt8CountIsLengthOutOfBounds) {
  const Bytes valid = encode(filled(Tag<cblox::camera_calibration_t>{}));
  const std::vector<TypeCase> cases = allCases();
  const TypeCase& c = findCase(cases, "camera_calibration_t");
  // num_distortion (int8) precedes 4 doubles and the 56-byte pose.
  Bytes bytes = valid;
  bytes[valid.size() - 56 - 32 - 1] = 0xFF;
  const WireCheck checked = check(c, bytes);
  EXPECT_EQ(checked.error, WireError::kLengthOutOfBounds);
  EXPECT_EQ(checked.detail, "field distortion: length -1 (num_distortion) is negative");
  EXPECT_THROW(c.unchecked_decode(bytes), std::length_error);
}

TEST(lcm_wire, StringLengthsAreBounded) {
  const std::vector<TypeCase> cases = allCases();
  const TypeCase& c = findCase(cases, "heartbeat_t");
  const Bytes valid = c.filled;
  constexpr size_t kProcessAt = 8 + 8;  // fingerprint, utime, then `process`
  Bytes bytes = valid;
  put32(&bytes, kProcessAt, 0);
  WireCheck checked = check(c, bytes);
  EXPECT_EQ(checked.error, WireError::kLengthOutOfBounds);
  EXPECT_EQ(checked.detail, "field process: string length 0 is below 1 (it counts the NUL)");

  put32(&bytes, kProcessAt, 0x00010000U);
  checked = check(c, bytes);
  EXPECT_EQ(checked.error, WireError::kLengthOutOfBounds);
  EXPECT_EQ(checked.detail, "field process: string length 65536 exceeds the " +
                                std::to_string(valid.size() - kProcessAt - 4) + " bytes left");

  // The last counter name: the path carries the element index.
  const size_t names_end = valid.size() - 8 * 2;  // two int64 counter values follow
  bytes = valid;
  put32(&bytes, names_end - 11 - 4, 0x80000000U);  // "frames_out" + NUL is 11 bytes
  checked = check(c, bytes);
  EXPECT_EQ(checked.error, WireError::kLengthOutOfBounds);
  EXPECT_EQ(checked.detail.rfind("field counter_names[1]: string length -2147483648", 0), 0U)
      << checked.detail;
}

TEST(lcm_wire, NestedMembersAreNamedByPath) {
  const std::vector<TypeCase> cases = allCases();
  {
    const cblox::stereo_pair_t msg = filled(Tag<cblox::stereo_pair_t>{});
    Bytes bytes = encode(msg);
    // fingerprint, utime, frame_id, left image, right.utime, then right.camera_id.
    const size_t at = 8 + 16 + static_cast<size_t>(msg.left.getEncodedSize() - 8) + 8;
    put32(&bytes, at, 0);
    const WireCheck checked = check(findCase(cases, "stereo_pair_t"), bytes);
    EXPECT_EQ(checked.error, WireError::kLengthOutOfBounds);
    EXPECT_EQ(checked.detail.rfind("field right.camera_id: string length 0", 0), 0U)
        << checked.detail;
  }
  {
    const cblox::covariance_reply_t msg = filled(Tag<cblox::covariance_reply_t>{});
    Bytes bytes = encode(msg);
    // fingerprint, utime, map_epoch, request_id, num_pairs, pairs[0], then pairs[1]'s
    // keyframe_i, keyframe_j, ok and error.
    const size_t at = 8 + 24 + static_cast<size_t>(msg.pairs[0].getEncodedSize() - 8) + 17;
    put32(&bytes, at, 0x7FFFFFFFU);
    const WireCheck checked = check(findCase(cases, "covariance_reply_t"), bytes);
    EXPECT_EQ(checked.error, WireError::kLengthOutOfBounds);
    EXPECT_EQ(checked.detail.rfind("field pairs[1].error: string length 2147483647", 0), 0U)
        << checked.detail;
    // Cut 104 bytes into pairs[1].sigma_i_given_j (after pairs[1].error, 4 + 22 bytes): the
    // bytes left cannot hold num_pairs = 2 pairs of at least 318 bytes.
    Bytes cut = encode(msg);
    cut.resize(at + 4 + 22 + 104);
    const WireCheck short_pairs = check(findCase(cases, "covariance_reply_t"), cut);
    EXPECT_EQ(short_pairs.error, WireError::kLengthOutOfBounds);
    EXPECT_EQ(short_pairs.detail,
              "field pairs: length 2 (num_pairs) x 318 bytes exceeds the " +
                  std::to_string(cut.size() - 32) + " bytes left");
  }
  {
    // stereo_pair_t ends with T_L_R (56 bytes) and rectified (1 byte): cut 10 bytes off, the
    // 23 bytes left cannot hold T_L_R.orientation's 4 doubles.
    Bytes cut = findCase(cases, "stereo_pair_t").filled;
    cut.resize(cut.size() - 10);
    const WireCheck truncated = check(findCase(cases, "stereo_pair_t"), cut);
    EXPECT_EQ(truncated.error, WireError::kTruncated);
    EXPECT_EQ(truncated.detail, "field T_L_R.orientation: needs 32 bytes, 23 left");
  }
}

TEST(lcm_wire, AnotherTypesBytesAreAFingerprintMismatch) {
  const std::vector<TypeCase> cases = allCases();
  for (const TypeCase& from : cases) {
    for (const TypeCase& as : cases) {
      if (from.name == as.name) continue;
      const Outcome out = as.decode(from.filled.data(), from.filled.size(), false);
      EXPECT_EQ(out.check.error, WireError::kFingerprintMismatch)
          << from.name << " as " << as.name;
    }
  }
  const TypeCase& pose = findCase(cases, "pose_t");
  const WireCheck checked = check(pose, findCase(cases, "keyframe_t").filled);
  EXPECT_EQ(checked.error, WireError::kFingerprintMismatch);
  EXPECT_EQ(checked.detail.rfind("fingerprint 0x", 0), 0U) << checked.detail;
  EXPECT_NE(checked.detail.find(" is not pose_t's 0x"), std::string::npos) << checked.detail;
}

TEST(lcm_wire, CutOrPaddedMessagesAreRefused) {
  for (const TypeCase& c : allCases()) {
    Bytes cut = c.filled;
    cut.pop_back();
    const WireError e = c.decode(cut.data(), cut.size(), false).check.error;
    EXPECT_TRUE(e == WireError::kTruncated || e == WireError::kLengthOutOfBounds)
        << c.name << ": " << cblox::wireErrorName(e);

    Bytes padded = c.filled;
    padded.push_back(0);
    EXPECT_EQ(c.decode(padded.data(), padded.size(), false).check.error,
              WireError::kTrailingBytes)
        << c.name;
    // LCM's own decode accepts the padded message: the byte-exact walk is stricter.
    EXPECT_EQ(c.unchecked_decode(padded), static_cast<int>(c.filled.size())) << c.name;

    for (size_t size = 0; size < 8; ++size) {
      EXPECT_EQ(c.decode(c.filled.data(), size, false).check.error, WireError::kTooShort);
    }
  }
  EXPECT_EQ(cblox::checkWire(nullptr, 0, "pose_t", cblox::pose_t::getHash()).error,
            WireError::kTooShort);
}

TEST(lcm_wire, UnknownTypeNameIsADecodeFailure) {
  const Bytes bytes = encode(filled(Tag<cblox::pose_t>{}));
  const WireCheck checked = cblox::checkWire(bytes.data(), bytes.size(), "nope_t", 0);
  EXPECT_EQ(checked.error, WireError::kDecodeFailed);
  EXPECT_EQ(checked.detail, "type nope_t is not in the wire schema");
}

TEST(lcm_wire, ErrorNamesAreDistinctSnakeCase) {
  std::set<std::string> names;
  for (int e = 0; e < static_cast<int>(WireError::kCount); ++e) {
    const std::string name = cblox::wireErrorName(static_cast<WireError>(e));
    EXPECT_EQ(name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_"), std::string::npos) << name;
    names.insert(name);
  }
  EXPECT_EQ(names.size(), static_cast<size_t>(WireError::kCount));
  EXPECT_STREQ(cblox::wireErrorName(WireError::kFingerprintMismatch), "fingerprint_mismatch");
  EXPECT_STREQ(cblox::wireErrorName(WireError::kCount), "invalid");
}

// ---------------------------------------------------------------------------------------
// The defect guarded against: the generated decode() on the same corruptions.

TEST(lcm_wire, UncheckedDecodeThrowsOrOverAllocates) {
  const std::vector<TypeCase> cases = allCases();
  {  // Negative count: vector::resize(-1) throws std::length_error.
    const TypeCase& c = findCase(cases, "keyframe_t");
    Bytes bytes = c.filled;
    put32(&bytes, bytes.size() - 4 - 8 * 4, 0xFFFFFFFFU);
    EXPECT_THROW(c.unchecked_decode(bytes), std::length_error);
    EXPECT_EQ(c.decode(bytes.data(), bytes.size(), false).check.error,
              WireError::kLengthOutOfBounds);
  }
  {  // String length 0: string::assign(p, -1) throws std::length_error.
    const TypeCase& c = findCase(cases, "heartbeat_t");
    Bytes bytes = c.filled;
    put32(&bytes, 16, 0);
    EXPECT_THROW(c.unchecked_decode(bytes), std::length_error);
    EXPECT_EQ(c.decode(bytes.data(), bytes.size(), false).check.error,
              WireError::kLengthOutOfBounds);
  }
  {  // A 16 MiB image size in a ~90-byte message: decode() allocates it before failing.
    const TypeCase& c = findCase(cases, "image_t");
    Bytes bytes = c.filled;
    const size_t data_bytes = filled(Tag<cblox::image_t>{}).data.size();  // `size` precedes it
    put32(&bytes, bytes.size() - data_bytes - 4, 0x01000000U);
    size_t largest = 0;
    int read = 0;
    {
      CountAllocations counting;
      read = c.unchecked_decode(bytes);
      largest = counting.largest();
    }
    EXPECT_LT(read, 0);
    EXPECT_GE(largest, size_t{1} << 24);
    const Outcome out = c.decode(bytes.data(), bytes.size(), false);
    EXPECT_EQ(out.check.error, WireError::kLengthOutOfBounds);
    EXPECT_LE(out.largest_allocation, bytes.size() + kAllocationSlack);
    std::printf("[ figures  ] image_t of %zu bytes with size 2^24: decode() allocates %zu bytes, "
                "decodeChecked() at most %zu\n",
                bytes.size(), largest, out.largest_allocation);
  }
}

// ---------------------------------------------------------------------------------------
// Thread safety and cost.

TEST(lcm_wire, ConcurrentChecksAgreeWithSequentialOnes) {
  const std::vector<TypeCase> cases = allCases();
  const auto run = [&cases] {
    std::vector<WireError> errors;
    for (const TypeCase& c : cases) {
      forEachMutation(c.filled, [&](Mutation, const Bytes& m) {
        errors.push_back(check(c, m).error);
      });
    }
    return errors;
  };
  const std::vector<WireError> sequential = run();
  std::array<std::vector<WireError>, 4> concurrent;
  std::vector<std::thread> threads;
  for (auto& result : concurrent) threads.emplace_back([&result, &run] { result = run(); });
  for (std::thread& t : threads) t.join();
  for (const auto& result : concurrent) EXPECT_EQ(result, sequential);
}

TEST(lcm_wire, CostOnAVgaImage) {
  cblox::image_t image = filled(Tag<cblox::image_t>{});
  image.width = 640;
  image.height = 480;
  image.row_stride = 640 * 3;
  image.size = image.row_stride * image.height;
  image.data.assign(static_cast<size_t>(image.size), 0x5A);
  const Bytes bytes = encode(image);
  using Clock = std::chrono::steady_clock;
  constexpr int kRepeats = 200;
  size_t passed = 0;
  auto start = Clock::now();
  for (int i = 0; i < kRepeats; ++i) {
    passed += cblox::checkWire(bytes.data(), bytes.size(), "image_t",
                               cblox::image_t::getHash()).ok();
  }
  const double check_us =
      std::chrono::duration<double, std::micro>(Clock::now() - start).count() / kRepeats;
  start = Clock::now();
  for (int i = 0; i < kRepeats; ++i) {
    cblox::image_t out;
    passed += out.decode(bytes.data(), 0, static_cast<int>(bytes.size())) > 0;
  }
  const double decode_us =
      std::chrono::duration<double, std::micro>(Clock::now() - start).count() / kRepeats;
  EXPECT_EQ(passed, 2U * kRepeats);
  std::printf("[ figures  ] %zu-byte image_t: checkWire %.2f us, decode %.1f us\n", bytes.size(),
              check_us, decode_us);
}

}  // namespace
