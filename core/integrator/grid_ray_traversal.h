#pragma once

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "core/tsdf/block_index.h"

namespace cblox {

/// Visits every cell of a regular grid crossed by the segment start -> end, in order
/// (Amanatides & Woo 3D DDA). Positions are in grid units (metres / cell size), so the
/// same traversal walks voxels or blocks. The first cell is the one containing `start`,
/// the last the one containing `end`; consecutive cells differ by one step along one
/// axis, and the walk always terminates (each step moves towards the end cell).
///
/// Usage: `for (GridRayTraversal t(a, b); ; ) { use(t.cell()); if (!t.advance()) break; }`
/// Not thread-safe (cheap to construct per ray).
class GridRayTraversal {
 public:
  /// `start` and `end` must be finite with |coordinates| < 2^31 (callers range-check).
  GridRayTraversal(const Eigen::Vector3f& start, const Eigen::Vector3f& end) {
    const Eigen::Vector3f delta = end - start;
    constexpr float kInf = std::numeric_limits<float>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
      cell_[axis] = fastFloor(start[axis]);
      end_cell_[axis] = fastFloor(end[axis]);
      step_[axis] = end_cell_[axis] > cell_[axis] ? 1 : (end_cell_[axis] < cell_[axis] ? -1 : 0);
      if (step_[axis] == 0 || delta[axis] == 0.0f) {
        // Nothing to do along this axis: its boundary never comes first.
        t_delta_[axis] = kInf;
        t_max_[axis] = kInf;
      } else {
        t_delta_[axis] = 1.0f / std::abs(delta[axis]);
        const float boundary_distance = step_[axis] > 0
                                            ? static_cast<float>(cell_[axis] + 1) - start[axis]
                                            : start[axis] - static_cast<float>(cell_[axis]);
        t_max_[axis] = boundary_distance * t_delta_[axis];
      }
    }
    remaining_ = (end_cell_ - cell_).cwiseAbs().sum();
  }

  const GridIndex& cell() const { return cell_; }
  /// Axis (0, 1, 2) of the last advance() and its direction (+1 or -1) along it.
  int lastAxis() const { return last_axis_; }
  int lastStep() const { return step_[last_axis_]; }

  /// Steps to the next cell; false when the current cell was the last one.
  bool advance() {
    if (remaining_ == 0) return false;
    // The axis whose boundary comes first; an axis that reached its end cell has its
    // boundary at infinity, so the walk only ever steps towards the end cell.
    const int axis =
        t_max_[0] < t_max_[1] ? (t_max_[0] < t_max_[2] ? 0 : 2) : (t_max_[1] < t_max_[2] ? 1 : 2);
    cell_[axis] += step_[axis];
    t_max_[axis] = cell_[axis] == end_cell_[axis] ? std::numeric_limits<float>::infinity()
                                                  : t_max_[axis] + t_delta_[axis];
    last_axis_ = axis;
    --remaining_;
    return true;
  }

 private:
  GridIndex cell_;
  GridIndex end_cell_;
  GridIndex step_;
  Eigen::Vector3f t_delta_;
  Eigen::Vector3f t_max_;
  int remaining_ = 0;
  int last_axis_ = 0;
};

}  // namespace cblox
