#pragma once

// The process's one libcamera::CameraManager (libcamera aborts when a second one is
// constructed), shared by every libcamera camera, and finding a camera in it.

#include <memory>
#include <string>
#include <vector>

#include <libcamera/camera.h>
#include <libcamera/camera_manager.h>

namespace cblox {

/// Returns the process-wide CameraManager, started. The first call constructs and starts it;
/// it is stopped and destroyed when the last returned pointer is released, and a later call
/// starts a new one (which rescans the cameras). Unless the environment sets
/// LIBCAMERA_LOG_LEVELS, libcamera's own log is limited to errors (its informational lines
/// and the "No IPA found" warning of Debian's package would otherwise go to stderr).
/// Returns nullptr and a message naming libcamera's error in *error (if non-null) when
/// CameraManager::start() fails. Thread-safe.
std::shared_ptr<libcamera::CameraManager> sharedCameraManager(std::string* error);

/// The ids of the cameras `manager` knows, in its order (index 0 first). Thread-safe.
std::vector<std::string> libcameraCameraIds(libcamera::CameraManager& manager);

/// "none" or the cameras as "0: <id>, 1: <id>"; for messages. Thread-safe.
std::string describeLibcameraCameras(libcamera::CameraManager& manager);

/// Finds a camera by `name`: an optional "libcamera:" prefix, then the camera's id exactly,
/// or else a decimal index into libcameraCameraIds(). Returns nullptr and, in *error (if
/// non-null), "libcamera camera '<name>' not found; cameras present: <list>" (the list as
/// describeLibcameraCameras()). Thread-safe.
std::shared_ptr<libcamera::Camera> findLibcameraCamera(libcamera::CameraManager& manager,
                                                       const std::string& name, std::string* error);

}  // namespace cblox
