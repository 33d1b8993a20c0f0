#include "core/optimization/cholmod_support.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cblox {

CholmodCommon::CholmodCommon() {
  cholmod_start(&common_);
  common_.print = 0;
  common_.error_handler = nullptr;
}

CholmodCommon::~CholmodCommon() { cholmod_finish(&common_); }

CholmodFactor& CholmodFactor::operator=(CholmodFactor&& other) noexcept {
  if (this != &other) {
    reset();
    factor_ = other.factor_;
    common_ = other.common_;
    other.factor_ = nullptr;
  }
  return *this;
}

void CholmodFactor::reset() {
  if (factor_ != nullptr) cholmod_free_factor(&factor_, common_->get());
  factor_ = nullptr;
}

cholmod_sparse cholmodUpperView(int n, int* p, int* i, double* x) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(n);
  view.ncol = static_cast<size_t>(n);
  view.nzmax = static_cast<size_t>(p[n]);
  view.p = p;
  view.i = i;
  view.nz = nullptr;
  view.x = x;
  view.z = nullptr;
  view.stype = 1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  return view;
}

CholmodSymmetricMatrix::CholmodSymmetricMatrix(const Eigen::SparseMatrix<double>& full)
    : upper_(full.triangularView<Eigen::Upper>()), diagonal_(full.diagonal()) {
  upper_.makeCompressed();
  view_ = cholmodUpperView(static_cast<int>(upper_.rows()), upper_.outerIndexPtr(),
                           upper_.innerIndexPtr(), upper_.valuePtr());
}

std::string validate(const CholmodFactorConfig& config) {
  if (config.kind != CholmodFactorKind::kAuto && config.kind != CholmodFactorKind::kSupernodal &&
      config.kind != CholmodFactorKind::kSimplicial) {
    return "kind must be kAuto, kSupernodal or kSimplicial";
  }
  if (!(config.auto_supernodal_flops_per_nonzero > 0.0) ||
      !std::isfinite(config.auto_supernodal_flops_per_nonzero)) {
    return "auto_supernodal_flops_per_nonzero must be > 0 and finite";
  }
  if (!(config.min_relative_pivot >= 0.0 && config.min_relative_pivot < 1.0)) {
    return "min_relative_pivot must be in [0, 1)";
  }
  return {};
}

std::string validateFactorField(const CholmodFactorConfig& config) {
  const std::string e = validate(config);
  return e.empty() ? e : "factor." + e;
}

namespace {

// L_kk for every k of a numeric LL^T factor.
Eigen::VectorXd factorDiagonal(const cholmod_factor& L) {
  const int n = static_cast<int>(L.n);
  Eigen::VectorXd d(n);
  const double* x = static_cast<const double*>(L.x);
  if (L.is_super) {
    const int* super = static_cast<const int*>(L.super);
    const int* pi = static_cast<const int*>(L.pi);
    const int* px = static_cast<const int*>(L.px);
    for (size_t s = 0; s < L.nsuper; ++s) {
      const int nrows = pi[s + 1] - pi[s];
      for (int c = super[s]; c < super[s + 1]; ++c) {
        const int offset = c - super[s];
        d[c] = x[px[s] + offset * nrows + offset];
      }
    }
  } else {
    const int* p = static_cast<const int*>(L.p);
    for (int c = 0; c < n; ++c) d[c] = x[p[c]];  // the diagonal comes first in its column
  }
  return d;
}

std::string describeColumn(int column, std::span<const std::uint64_t> keyframe_ids) {
  std::ostringstream s;
  s << "column " << column;
  if (column >= 0 && column / 6 < static_cast<int>(keyframe_ids.size())) {
    s << " (keyframe " << keyframe_ids[column / 6] << ")";
  }
  return s.str();
}

}  // namespace

CholmodFactorOutcome factorizeWithPermutation(CholmodCommon& common, CholmodSymmetricMatrix& A,
                                              std::span<const int> perm,
                                              const CholmodFactorConfig& config,
                                              std::span<const std::uint64_t> keyframe_ids) {
  cholmod_common* c = common.get();
  c->nmethods = 1;
  c->method[0].ordering = CHOLMOD_GIVEN;
  c->postorder = 0;
  switch (config.kind) {
    case CholmodFactorKind::kAuto:
      c->supernodal = CHOLMOD_AUTO;
      break;
    case CholmodFactorKind::kSupernodal:
      c->supernodal = CHOLMOD_SUPERNODAL;
      break;
    case CholmodFactorKind::kSimplicial:
      c->supernodal = CHOLMOD_SIMPLICIAL;
      break;
  }
  c->supernodal_switch = config.auto_supernodal_flops_per_nonzero;
  c->final_ll = 1;
  c->status = CHOLMOD_OK;
  const int n = A.size();
  CholmodFactorOutcome out;
  if (static_cast<int>(perm.size()) != n) {
    out.error = "permutation has " + std::to_string(perm.size()) + " entries, expected " +
                std::to_string(n);
    return out;
  }
  // CHOLMOD's API takes a non-const Perm although it does not write it.
  std::vector<int> perm_copy(perm.begin(), perm.end());
  out.factor = CholmodFactor(cholmod_analyze_p(A.get(), perm_copy.data(), nullptr, 0, c), &common);
  if (!out.factor || c->status < CHOLMOD_OK) {
    out.error = "CHOLMOD analysis failed (status " + std::to_string(c->status) + ")";
    return out;
  }
  const int* L_perm = static_cast<const int*>(out.factor.get()->Perm);
  if (!std::equal(perm.begin(), perm.end(), L_perm)) {
    out.error = "CHOLMOD did not keep the given permutation";
    return out;
  }
  cholmod_factorize(A.get(), out.factor.get(), c);
  const cholmod_factor& L = *out.factor.get();
  if (c->status == CHOLMOD_NOT_POSDEF || static_cast<int>(L.minor) < n) {
    const int k = static_cast<int>(L.minor);
    out.error = std::string(kNotPositiveDefiniteError) + " (CHOLMOD: non-positive pivot at " +
                describeColumn(k < n ? perm[k] : -1, keyframe_ids) + ")";
    return out;
  }
  if (c->status < CHOLMOD_OK) {
    out.error = "CHOLMOD factorisation failed (status " + std::to_string(c->status) + ")";
    return out;
  }
  const Eigen::VectorXd d = factorDiagonal(L);
  const Eigen::VectorXd& a = A.diagonal();
  int worst = -1;
  double worst_ratio = 1.0;
  for (int k = 0; k < n; ++k) {
    const double ratio = d[k] * d[k] / a[perm[k]];
    if (!(ratio >= worst_ratio)) {
      worst_ratio = ratio;
      worst = k;
    }
  }
  if (worst >= 0 && !(worst_ratio >= config.min_relative_pivot)) {
    std::ostringstream s;
    s << kNotPositiveDefiniteError << " (relative pivot " << worst_ratio << " < "
      << config.min_relative_pivot << " at " << describeColumn(perm[worst], keyframe_ids) << ")";
    out.error = s.str();
    return out;
  }
  out.ok = true;
  return out;
}

Eigen::MatrixXd trailingFactorBlock(const cholmod_factor& L, int t) {
  const int n = static_cast<int>(L.n);
  const int first = n - t;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(t, t);
  const double* x = static_cast<const double*>(L.x);
  if (L.is_super) {
    const int* super = static_cast<const int*>(L.super);
    const int* pi = static_cast<const int*>(L.pi);
    const int* px = static_cast<const int*>(L.px);
    const int* rows = static_cast<const int*>(L.s);
    for (int s = static_cast<int>(L.nsuper) - 1; s >= 0 && super[s + 1] > first; --s) {
      const int k1 = super[s];
      const int nrows = pi[s + 1] - pi[s];
      for (int c = std::max(k1, first); c < super[s + 1]; ++c) {
        const double* column = x + px[s] + static_cast<std::ptrdiff_t>(c - k1) * nrows;
        for (int q = c - k1; q < nrows; ++q) {  // rows before c - k1 are above the diagonal
          M(rows[pi[s] + q] - first, c - first) = column[q];
        }
      }
    }
  } else {
    const int* p = static_cast<const int*>(L.p);
    const int* i = static_cast<const int*>(L.i);
    const int* nz = static_cast<const int*>(L.nz);
    for (int c = first; c < n; ++c) {
      for (int q = p[c]; q < p[c] + nz[c]; ++q) M(i[q] - first, c - first) = x[q];
    }
  }
  return M;
}

CholmodFactorOutcome factorizeSimplicialWithPermutation(
    CholmodCommon& common, CholmodSymmetricMatrix& A, std::span<const int> perm,
    const CholmodFactorConfig& config, std::span<const std::uint64_t> keyframe_ids) {
  CholmodFactorOutcome f = factorizeWithPermutation(common, A, perm, config, keyframe_ids);
  if (!f.ok) return f;
  cholmod_factor* L = f.factor.get();
  if ((L->is_super || !L->is_ll) &&
      !cholmod_change_factor(CHOLMOD_REAL, 1, 0, 1, 1, L, common.get())) {
    f.factor.reset();
    f.ok = false;
    f.error = "CHOLMOD could not convert the factor to simplicial LL^T";
  }
  return f;
}

}  // namespace cblox
