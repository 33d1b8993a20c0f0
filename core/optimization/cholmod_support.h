#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <cholmod.h>
#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace cblox {

/// Thin RAII layer over SuiteSparse CHOLMOD (Debian's SuiteSparse 5.12, 32-bit int API) for
/// the sparse reduced camera system of our bundle adjustment (reduced_camera_system.h) and
/// the covariance solvers (core/covariance).

/// RAII owner of one cholmod_common (cholmod_start / cholmod_finish). CHOLMOD keeps its
/// workspace in it, so it must not be used by two threads at once: every solver object owns
/// one and is therefore not thread-safe (distinct objects may run on distinct threads).
/// Diagnostics printing is switched off (errors are reported through `status`).
class CholmodCommon {
 public:
  CholmodCommon();
  ~CholmodCommon();
  CholmodCommon(const CholmodCommon&) = delete;
  CholmodCommon& operator=(const CholmodCommon&) = delete;
  cholmod_common* get() { return &common_; }

 private:
  cholmod_common common_;
};

/// RAII owner of a cholmod_factor allocated with `common` (which must outlive it).
/// Move-only. Not thread-safe.
class CholmodFactor {
 public:
  CholmodFactor() = default;
  CholmodFactor(cholmod_factor* factor, CholmodCommon* common) : factor_(factor), common_(common) {}
  ~CholmodFactor() { reset(); }
  CholmodFactor(CholmodFactor&& other) noexcept { *this = std::move(other); }
  CholmodFactor& operator=(CholmodFactor&& other) noexcept;
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;
  void reset();
  cholmod_factor* get() const { return factor_; }
  explicit operator bool() const { return factor_ != nullptr; }

 private:
  cholmod_factor* factor_ = nullptr;
  CholmodCommon* common_ = nullptr;
};

/// CHOLMOD's view (not a copy) of a symmetric n x n matrix given by its upper triangle in
/// packed compressed columns with sorted rows (stype = 1: entries below the diagonal are
/// ignored): column pointers p (n + 1), row indices i and values x (p[n] each). The arrays
/// must outlive the view. Thread-safe (pure).
cholmod_sparse cholmodUpperView(int n, int* p, int* i, double* x);

/// A symmetric matrix in CHOLMOD's layout: its upper triangle (stype = 1), packed, sorted,
/// stored here and viewed (not copied) by CHOLMOD. Immutable after construction; get()
/// returns a non-const pointer only because CHOLMOD's API is not const-correct.
class CholmodSymmetricMatrix {
 public:
  /// `full`: square, both triangles stored (e.g. ReducedCameraMatrix::matrix).
  explicit CholmodSymmetricMatrix(const Eigen::SparseMatrix<double>& full);
  CholmodSymmetricMatrix(const CholmodSymmetricMatrix&) = delete;
  CholmodSymmetricMatrix& operator=(const CholmodSymmetricMatrix&) = delete;
  cholmod_sparse* get() { return &view_; }
  int size() const { return static_cast<int>(upper_.rows()); }
  /// The diagonal entries (for the relative pivot test).
  const Eigen::VectorXd& diagonal() const { return diagonal_; }

 private:
  Eigen::SparseMatrix<double> upper_;
  Eigen::VectorXd diagonal_;
  cholmod_sparse view_{};
};

/// Measured per-pair factorisation (cblox-bench-covariance, Debian's ATLAS BLAS), supernodal
/// vs simplicial: 500 keyframes, two-lap loop (223 Mflop, 280 flops per nonzero of L):
/// 82 vs 115 ms; 500 keyframes, one lap (20 Mflop, 81 flops/nnz): 37 vs 14 ms; 50
/// keyframes, two laps (92 flops/nnz): 4.0 vs 2.8 ms. Hence kAuto's switch at 150.
enum class CholmodFactorKind {
  kAuto,        ///< supernodal iff flops / nnz(L) >= auto_supernodal_flops_per_nonzero
  kSupernodal,  ///< supernodal LL^T (BLAS-3 on dense supernodes): best when the fill is dense
  kSimplicial,  ///< simplicial LL^T (column by column): best for very sparse factors
};

/// How the solvers factorise S.
struct CholmodFactorConfig {
  CholmodFactorKind kind = CholmodFactorKind::kAuto;
  /// kAuto's switch (CHOLMOD's supernodal_switch): supernodal when the factorisation's
  /// flops per nonzero of L reach this. Default 150 (measured crossover, see above); > 0.
  double auto_supernodal_flops_per_nonzero = 150.0;
  /// The factorisation is rejected as "not positive definite" if CHOLMOD finds a
  /// non-positive pivot or if some pivot is relatively tiny: L_kk^2 <
  /// min_relative_pivot * A_kk (dimensionless; L_kk^2 / A_kk is in (0, 1] for a positive
  /// definite A and ~1e-16..1e-12 in a gauge (null-space) direction). Default 1e-10;
  /// must be in [0, 1).
  double min_relative_pivot = 1e-10;
};

/// Empty if valid, else a message naming the bad field. Thread-safe (pure).
std::string validate(const CholmodFactorConfig& config);

/// validate(config) prefixed with "factor." (for the solver configs' `factor` field).
/// Thread-safe (pure).
std::string validateFactorField(const CholmodFactorConfig& config);

/// Result of factorize(): the factor if ok, else an error message.
struct CholmodFactorOutcome {
  CholmodFactor factor;
  bool ok = false;
  std::string error;
};

/// Cholesky factorisation P A P^T = L L^T with the scalar permutation `perm` (perm[k] =
/// the row of A that is k-th pivot) forced on CHOLMOD: nmethods = 1, CHOLMOD_GIVEN,
/// postorder off, so L's row/column k is A's perm[k] (checked: L->Perm == perm). Not
/// positive definite (CHOLMOD's test or the relative pivot test) gives ok = false and an
/// error that names the keyframe of the failing column (`keyframe_ids[column / 6]`).
/// Not thread-safe (uses `common`).
CholmodFactorOutcome factorizeWithPermutation(CholmodCommon& common, CholmodSymmetricMatrix& A,
                                              std::span<const int> perm,
                                              const CholmodFactorConfig& config,
                                              std::span<const std::uint64_t> keyframe_ids);

/// factorizeWithPermutation() followed, on success, by the conversion of the factor to a
/// simplicial, packed, monotonic LL^T (column c of L is rows i[p[c]..p[c] + nz[c]), diagonal
/// first), which the sparse-inverse and sparse-solve solvers walk column by column. A failed
/// conversion gives ok = false with its own message. Not thread-safe (uses `common`).
CholmodFactorOutcome factorizeSimplicialWithPermutation(
    CholmodCommon& common, CholmodSymmetricMatrix& A, std::span<const int> perm,
    const CholmodFactorConfig& config, std::span<const std::uint64_t> keyframe_ids);

/// The trailing t x t block of L (rows and columns n - t .. n - 1), lower triangular, read
/// directly from a supernodal factor's supernodes or from a simplicial LL^T factor.
/// Precondition: `L` is a numeric LL^T factor (supernodal, or simplicial with is_ll).
/// Thread-safe (reads only).
Eigen::MatrixXd trailingFactorBlock(const cholmod_factor& L, int t);

/// "reduced camera matrix is not positive definite: is the gauge fixed?" (the prefix of
/// every not-positive-definite error of the solvers).
inline constexpr const char* kNotPositiveDefiniteError =
    "reduced camera matrix is not positive definite: is the gauge fixed?";

}  // namespace cblox
