#pragma once

// The mapper's keyframe and landmark keys: the tracker numbers keyframes and landmarks
// afresh in every map epoch (a restarted source starts a new map), so the mapper keys them by
// (epoch, id), packed into one int64 that its subvolumes, covisibility graph and fusion
// scheduler use as they used plain ids: key = epoch * 2^40 + id. Epoch 0 keys are the ids.

#include <cstdint>
#include <optional>

namespace cblox {

inline constexpr int kEpochKeyShift = 40;
inline constexpr int64_t kMaxIdInEpoch = (int64_t{1} << kEpochKeyShift) - 1;
inline constexpr int32_t kMaxMapEpoch = (int32_t{1} << (62 - kEpochKeyShift)) - 1;

/// The key of `id` in map `epoch`; nullopt when the id is outside [0, 2^40) or the epoch
/// outside [0, 2^22). Thread-safe (pure).
inline std::optional<int64_t> epochKey(int32_t epoch, int64_t id) {
  if (epoch < 0 || epoch > kMaxMapEpoch || id < 0 || id > kMaxIdInEpoch) return std::nullopt;
  return (static_cast<int64_t>(epoch) << kEpochKeyShift) | id;
}
/// The epoch and the id of a key made by epochKey(). Thread-safe (pure).
inline int32_t epochOfKey(int64_t key) { return static_cast<int32_t>(key >> kEpochKeyShift); }
inline int64_t idOfKey(int64_t key) { return key & kMaxIdInEpoch; }

}  // namespace cblox
