#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace cblox {

/// Parameters of the procedural surface texture that gives simulated images their features.
struct ProceduralTextureConfig {
  /// Wavelength of the coarsest noise octave, metres. Each further octave halves it.
  double base_wavelength_m = 0.4;
  /// Number of octaves (1..8).
  int octaves = 5;
  /// Amplitude ratio of each octave to the previous, in (0, 2]: 1 gives every scale the
  /// same contrast (fine grain as strong as the blobs), smaller values smoother surfaces.
  double persistence = 0.85;
  /// Brightness spread: the factor ranges over [1 - contrast, 1]. In [0, 1].
  double contrast = 0.75;
  /// Share of hard-edged blobs (the thresholded third octave) mixed into the smooth noise; hard edges
  /// make corners for feature detectors. In [0, 1].
  double hard_edge_share = 0.35;
  /// Seed of the noise lattice; the same seed gives the same texture.
  uint32_t seed = 1;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// A deterministic, anti-aliased 2D value-noise texture applied tri-planarly in world
/// coordinates (the plane is chosen by the surface normal's largest component), so it needs
/// no texture coordinates and looks the same from every camera (stereo-consistent). Octaves
/// finer than about two pixel footprints fade to their mean, which keeps distant surfaces
/// from aliasing into noise. The value is normalised by the weight of all octaves, so a
/// faded octave contributes its mean (0.5).
/// Thread-safety: immutable after construction; brightness() is thread-safe.
class ProceduralTexture {
 public:
  /// Throws std::invalid_argument with validate()'s message if the config is invalid.
  explicit ProceduralTexture(const ProceduralTextureConfig& config);

  /// Brightness factor in [1 - contrast, 1] at world point p (metres) on a surface with
  /// normal n (any length), seen with a pixel footprint of `footprint_m` metres (the size of
  /// one pixel on the surface; 0 renders every octave). Thread-safe.
  float brightness(const Eigen::Vector3f& p, const Eigen::Vector3f& n, float footprint_m) const;

  /// One sample for the batched brightness(): world point, surface normal, pixel footprint.
  struct TextureSample {
    Eigen::Vector3f point;
    Eigen::Vector3f normal;
    float footprint_m;
  };

  /// out[i] = brightness(samples[i]...) for i < min(samples.size(), out.size()), eight at a
  /// time with SIMD; the single-sample overload calls this, so both give identical values.
  /// Thread-safe.
  void brightness(std::span<const TextureSample> samples, std::span<float> out) const;

  const ProceduralTextureConfig& config() const { return config_; }

 private:
  static constexpr int kLatticeSize = 256;  // power of two: wraps with a mask
  static constexpr int kLatticeStride = kLatticeSize + 4;  // row + its first 4 bytes again

  float totalWeight() const;
  /// Tri-planar coordinates, plane offset and wavelength/footprint ratio of 8 lanes from
  /// samples[start, start + count) (the last sample repeated past count).
  void prepareLanes(std::span<const TextureSample> samples, size_t start, size_t count,
                    float* s, float* t, float* offset, float* ratio) const;
  void brightnessPortable(std::span<const TextureSample> samples, std::span<float> out) const;
  void brightnessAvx2(std::span<const TextureSample> samples, std::span<float> out) const;

 public:
  /// Which implementation brightness() uses: AVX2/FMA when the CPU has them (chosen at
  /// construction), else portable vector code. For tests and benchmarks.
  bool usesAvx2() const { return use_avx2_; }
  /// Not thread-safe: call before the texture is shared.
  void setUseAvx2(bool use) {
    use_avx2_ = use && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }

 private:

  ProceduralTextureConfig config_;
  std::vector<uint8_t> lattice_;  // kLatticeSize rows of kLatticeStride bytes, 0..255 = [0, 1]
  bool use_avx2_ = false;
};

}  // namespace cblox
