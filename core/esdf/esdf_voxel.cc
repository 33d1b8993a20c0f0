#include "core/esdf/esdf_voxel.h"

namespace cblox {

const char* voxelStateName(VoxelState state) {
  switch (state) {
    case VoxelState::kFree:
      return "free";
    case VoxelState::kOccupied:
      return "occupied";
    case VoxelState::kUnknown:
      break;
  }
  return "unknown";
}

}  // namespace cblox
