#include "core/raycast/triangle_mesh_raycaster.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/geometry/closest_point_on_triangle.h"

namespace cblox {

struct TriangleMeshRaycaster::EmbreeHandles {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::string last_error;  // written by the device error callback during create() only

  ~EmbreeHandles() {
    if (scene != nullptr) rtcReleaseScene(scene);
    if (device != nullptr) rtcReleaseDevice(device);
  }
};

namespace {

void onEmbreeError(void* user, RTCError code, const char* message) {
  auto* text = static_cast<std::string*>(user);
  *text = "Embree error " + std::to_string(static_cast<int>(code)) + ": " +
          (message != nullptr ? message : "(no message)");
}

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

struct PointQueryState {
  const Mesh* mesh;
  Eigen::Vector3d p;
  ClosestSurfacePoint* result;
};

bool pointQueryCallback(RTCPointQueryFunctionArguments* args) {
  auto* state = static_cast<PointQueryState*>(args->userPtr);
  const Eigen::Vector3i& tri = state->mesh->triangles[args->primID];
  const auto& vertices = state->mesh->vertices;
  const Eigen::Vector3d closest = closestPointOnTriangle(
      state->p, vertices[tri[0]].cast<double>(), vertices[tri[1]].cast<double>(),
      vertices[tri[2]].cast<double>());
  const double distance = (closest - state->p).norm();
  if (distance < state->result->distance) {
    state->result->distance = distance;
    state->result->point = closest;
    state->result->triangle = args->primID;
    // Shrink the search sphere (slightly enlarged so float rounding never prunes a triangle
    // that is as close in double precision).
    const float radius = static_cast<float>(distance) * (1.0f + 1e-6f) + 1e-7f;
    if (radius < args->query->radius) {
      args->query->radius = radius;
      return true;
    }
  }
  return false;
}

}  // namespace

std::unique_ptr<TriangleMeshRaycaster> TriangleMeshRaycaster::create(const Mesh& mesh,
                                                                     std::string* error) {
  if (const std::string problem = mesh.validate(); !problem.empty()) {
    setError(error, "invalid mesh: " + problem);
    return nullptr;
  }
  if (mesh.triangles.empty()) {
    setError(error, "mesh has no triangle (" + std::to_string(mesh.numVertices()) +
                        " vertices): nothing to ray-trace");
    return nullptr;
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      setError(error, "mesh vertex " + std::to_string(i) + " is not finite");
      return nullptr;
    }
  }

  std::unique_ptr<TriangleMeshRaycaster> raycaster(new TriangleMeshRaycaster());
  raycaster->mesh_ = mesh;
  raycaster->bounds_.setEmpty();
  for (const Eigen::Vector3f& v : mesh.vertices) raycaster->bounds_.extend(v);
  raycaster->triangle_normals_.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[t[0]];
    const Eigen::Vector3f n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
    const float norm = n.norm();
    raycaster->triangle_normals_.push_back(norm > 0.0f ? Eigen::Vector3f(n / norm)
                                                       : Eigen::Vector3f::Zero());
  }
  raycaster->embree_ = std::make_unique<EmbreeHandles>();
  EmbreeHandles& handles = *raycaster->embree_;

  handles.device = rtcNewDevice(nullptr);
  if (handles.device == nullptr) {
    setError(error, "Embree: cannot create a device (error " +
                        std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
    return nullptr;
  }
  rtcSetDeviceErrorFunction(handles.device, onEmbreeError, &handles.last_error);

  handles.scene = rtcNewScene(handles.device);
  rtcSetSceneBuildQuality(handles.scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = rtcNewGeometry(handles.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
      mesh.vertices.size()));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
      mesh.triangles.size()));
  if (vertices == nullptr || indices == nullptr) {
    rtcReleaseGeometry(geometry);
    setError(error, "Embree: cannot allocate geometry buffers: " + handles.last_error);
    return nullptr;
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    std::memcpy(vertices + 3 * i, mesh.vertices[i].data(), 3 * sizeof(float));
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) indices[3 * i + k] = static_cast<uint32_t>(mesh.triangles[i][k]);
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometryByID(handles.scene, geometry, 0);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(handles.scene);
  if (rtcGetDeviceError(handles.device) != RTC_ERROR_NONE || !handles.last_error.empty()) {
    setError(error, "Embree: building the scene failed: " + handles.last_error);
    return nullptr;
  }
  return raycaster;
}

TriangleMeshRaycaster::~TriangleMeshRaycaster() = default;

bool TriangleMeshRaycaster::intersect(const Ray& ray, RaycastHit* hit) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rayhit;
  rayhit.ray.org_x = ray.origin.x();
  rayhit.ray.org_y = ray.origin.y();
  rayhit.ray.org_z = ray.origin.z();
  rayhit.ray.dir_x = ray.direction.x();
  rayhit.ray.dir_y = ray.direction.y();
  rayhit.ray.dir_z = ray.direction.z();
  rayhit.ray.tnear = ray.t_near;
  rayhit.ray.tfar = ray.t_far;
  rayhit.ray.time = 0.0f;
  rayhit.ray.mask = 0xFFFFFFFFu;
  rayhit.ray.id = 0;
  rayhit.ray.flags = 0;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(embree_->scene, &context, &rayhit);
  *hit = RaycastHit();
  if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit->t = rayhit.ray.tfar;
  hit->triangle = rayhit.hit.primID;
  hit->u = rayhit.hit.u;
  hit->v = rayhit.hit.v;
  hit->normal = triangle_normals_[rayhit.hit.primID];
  return true;
}

void TriangleMeshRaycaster::tracePacket(::RTCRayHit16* packet, const int* valid, size_t count,
                                        RaycastHit* hits) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  rtcIntersect16(valid, embree_->scene, &context, packet);
  for (size_t k = 0; k < count; ++k) {
    RaycastHit& hit = hits[k];
    const unsigned triangle = packet->hit.geomID[k] == RTC_INVALID_GEOMETRY_ID
                                  ? RaycastHit::kNoHit
                                  : packet->hit.primID[k];
    hit.triangle = triangle;
    if (triangle == RaycastHit::kNoHit) {
      hit.t = std::numeric_limits<float>::infinity();
      hit.u = hit.v = 0.0f;
      hit.normal.setZero();
      continue;
    }
    hit.t = packet->ray.tfar[k];
    hit.u = packet->hit.u[k];
    hit.v = packet->hit.v[k];
    hit.normal = triangle_normals_[triangle];
  }
}

namespace {

/// Fills lane k of a packet; lanes past `count` repeat the last ray and are masked off.
void setLane(RTCRayHit16* packet, int k, const Eigen::Vector3f& origin,
             const Eigen::Vector3f& direction, float t_near, float t_far) {
  packet->ray.org_x[k] = origin.x();
  packet->ray.org_y[k] = origin.y();
  packet->ray.org_z[k] = origin.z();
  packet->ray.dir_x[k] = direction.x();
  packet->ray.dir_y[k] = direction.y();
  packet->ray.dir_z[k] = direction.z();
  packet->ray.tnear[k] = t_near;
  packet->ray.tfar[k] = t_far;
  packet->ray.time[k] = 0.0f;
  packet->ray.mask[k] = 0xFFFFFFFFu;
  packet->ray.id[k] = static_cast<unsigned>(k);
  packet->ray.flags[k] = 0;
  packet->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
  packet->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
}

}  // namespace

void TriangleMeshRaycaster::intersect(std::span<const Ray> rays,
                                      std::span<RaycastHit> hits) const {
  constexpr size_t kPacket = 16;
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[kPacket];
  const size_t count = std::min(rays.size(), hits.size());
  for (size_t start = 0; start < count; start += kPacket) {
    const size_t n = std::min(kPacket, count - start);
    for (size_t k = 0; k < kPacket; ++k) {
      valid[k] = k < n ? -1 : 0;
      const Ray& ray = rays[start + std::min(k, n - 1)];
      setLane(&packet, static_cast<int>(k), ray.origin, ray.direction, ray.t_near, ray.t_far);
    }
    tracePacket(&packet, valid, n, hits.data() + start);
  }
}

void TriangleMeshRaycaster::intersectPinholeRows(const Eigen::Matrix3f& R_G_C,
                                                 const Eigen::Vector3f& origin_G,
                                                 const PinholeIntrinsics& intrinsics,
                                                 int row_begin, int row_end,
                                                 std::span<RaycastHit> hits) const {
  // 4 x 4 pixel tiles: more coherent packets than 16 pixels of one row.
  constexpr int kTile = 4;
  const int width = intrinsics.width;
  const float fx = static_cast<float>(intrinsics.fx), fy = static_cast<float>(intrinsics.fy);
  const float cx = static_cast<float>(intrinsics.cx), cy = static_cast<float>(intrinsics.cy);
  const float inf = std::numeric_limits<float>::infinity();
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[16];
  RaycastHit tile_hits[16];
  for (int v0 = row_begin; v0 < row_end; v0 += kTile) {
    for (int u0 = 0; u0 < width; u0 += kTile) {
      int count = 0;
      for (int k = 0; k < 16; ++k) {
        const int u = u0 + (k % kTile), v = v0 + (k / kTile);
        const bool inside = u < width && v < row_end;
        valid[k] = inside ? -1 : 0;
        count = inside ? k + 1 : count;
        const Eigen::Vector3f direction =
            R_G_C * Eigen::Vector3f((static_cast<float>(std::min(u, width - 1)) - cx) / fx,
                                    (static_cast<float>(std::min(v, row_end - 1)) - cy) / fy, 1.0f);
        setLane(&packet, k, origin_G, direction, 0.0f, inf);
      }
      tracePacket(&packet, valid, static_cast<size_t>(count), tile_hits);
      for (int k = 0; k < 16; ++k) {
        const int u = u0 + (k % kTile), v = v0 + (k / kTile);
        if (u < width && v < row_end) {
          hits[static_cast<size_t>(v - row_begin) * width + u] = tile_hits[k];
        }
      }
    }
  }
}

bool TriangleMeshRaycaster::occluded(const Ray& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay shadow;
  shadow.org_x = ray.origin.x();
  shadow.org_y = ray.origin.y();
  shadow.org_z = ray.origin.z();
  shadow.dir_x = ray.direction.x();
  shadow.dir_y = ray.direction.y();
  shadow.dir_z = ray.direction.z();
  shadow.tnear = ray.t_near;
  shadow.tfar = ray.t_far;
  shadow.time = 0.0f;
  shadow.mask = 0xFFFFFFFFu;
  shadow.id = 0;
  shadow.flags = 0;
  rtcOccluded1(embree_->scene, &context, &shadow);
  return shadow.tfar < 0.0f;  // Embree sets tfar to -inf when occluded
}

ClosestSurfacePoint TriangleMeshRaycaster::closestPoint(const Eigen::Vector3d& p,
                                                        double max_distance) const {
  ClosestSurfacePoint result;
  if (!p.allFinite() || !(max_distance >= 0.0)) return result;
  RTCPointQuery query;
  query.x = static_cast<float>(p.x());
  query.y = static_cast<float>(p.y());
  query.z = static_cast<float>(p.z());
  query.time = 0.0f;
  query.radius = std::isfinite(max_distance) ? static_cast<float>(max_distance) * (1.0f + 1e-6f)
                                             : std::numeric_limits<float>::infinity();
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  PointQueryState state{&mesh_, p, &result};
  rtcPointQuery(embree_->scene, &query, &context, pointQueryCallback, &state);
  if (result.found() && result.distance > max_distance) result = ClosestSurfacePoint();
  return result;
}

}  // namespace cblox
