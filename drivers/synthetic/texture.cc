#include "drivers/synthetic/texture.h"

#include <cmath>

namespace cblox {

Color CheckerTexture::colorAt(const Eigen::Vector2d& uv) const {
  if (!(cell_size > 0.0) || !std::isfinite(cell_size)) return a;
  const double iu = std::floor(uv.x() / cell_size);
  const double iv = std::floor(uv.y() / cell_size);
  if (!std::isfinite(iu) || !std::isfinite(iv)) return a;
  // fmod keeps the parity exact for cell indices far beyond the int range.
  const double parity = std::fmod(std::fabs(iu + iv), 2.0);
  return parity < 0.5 ? a : b;
}

}  // namespace cblox
