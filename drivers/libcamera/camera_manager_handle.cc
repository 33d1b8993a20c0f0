#include "drivers/libcamera/camera_manager_handle.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace cblox {
namespace {

constexpr const char* kPrefix = "libcamera:";

std::mutex& managerMutex() {
  static std::mutex mutex;
  return mutex;
}

std::weak_ptr<libcamera::CameraManager>& currentManager() {
  static std::weak_ptr<libcamera::CameraManager> manager;
  return manager;
}

bool isIndex(const std::string& text) {
  return !text.empty() && text.size() < 6 &&
         std::all_of(text.begin(), text.end(),
                     [](unsigned char c) { return std::isdigit(c) != 0; });
}

}  // namespace

std::shared_ptr<libcamera::CameraManager> sharedCameraManager(std::string* error) {
  const std::lock_guard<std::mutex> lock(managerMutex());
  if (std::shared_ptr<libcamera::CameraManager> manager = currentManager().lock()) return manager;
  // libcamera reads its log levels once, when it logs first; 0 = keep the user's setting.
  setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
  auto created = std::make_unique<libcamera::CameraManager>();
  const int result = created->start();
  if (result < 0) {
    if (error != nullptr) {
      *error = std::string("libcamera: cannot start the camera manager: ") + std::strerror(-result);
    }
    return nullptr;
  }
  // The deleter stops the manager: every camera of it has been released by then, as each
  // holder of a camera also holds this pointer.
  std::shared_ptr<libcamera::CameraManager> manager(created.release(),
                                                    [](libcamera::CameraManager* m) {
                                                      m->stop();
                                                      delete m;
                                                    });
  currentManager() = manager;
  return manager;
}

std::vector<std::string> libcameraCameraIds(libcamera::CameraManager& manager) {
  std::vector<std::string> ids;
  for (const std::shared_ptr<libcamera::Camera>& camera : manager.cameras()) {
    ids.push_back(camera->id());
  }
  return ids;
}

std::string describeLibcameraCameras(libcamera::CameraManager& manager) {
  const std::vector<std::string> ids = libcameraCameraIds(manager);
  if (ids.empty()) return "none";
  std::string text;
  for (size_t i = 0; i < ids.size(); ++i) {
    if (i > 0) text += ", ";
    text += std::to_string(i) + ": " + ids[i];
  }
  return text;
}

std::shared_ptr<libcamera::Camera> findLibcameraCamera(libcamera::CameraManager& manager,
                                                       const std::string& name,
                                                       std::string* error) {
  const std::string id = name.rfind(kPrefix, 0) == 0 ? name.substr(std::strlen(kPrefix)) : name;
  const std::vector<std::shared_ptr<libcamera::Camera>> cameras = manager.cameras();
  for (const std::shared_ptr<libcamera::Camera>& camera : cameras) {
    if (camera->id() == id) return camera;
  }
  if (isIndex(id)) {
    const size_t index = static_cast<size_t>(std::stoul(id));
    if (index < cameras.size()) return cameras[index];
  }
  if (error != nullptr) {
    *error = "libcamera camera '" + id +
             "' not found; cameras present: " + describeLibcameraCameras(manager);
  }
  return nullptr;
}

}  // namespace cblox
