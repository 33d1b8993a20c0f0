#include "core/persistence/id_lease.h"

#include <filesystem>

#include "core/io/atomic_file.h"
#include "core/persistence/byte_codec.h"
#include "core/persistence/map_file_header.h"

namespace cblox {

namespace {
constexpr std::string_view kIdLeaseMagic = "CBLOXLSE";
constexpr uint32_t kIdLeaseVersion = 1;

std::string leasePath(const std::string& dir) {
  return (std::filesystem::path(dir) / kIdLeaseFileName).string();
}
}  // namespace

bool writeIdLease(const std::string& dir, const IdLease& lease, std::string* error) {
  std::string payload;
  persistence_detail::ByteWriter w(&payload);
  w.i32(lease.map_epoch);
  w.i64(lease.keyframe_floor);
  w.u64(lease.landmark_floor);
  return writeFileAtomically(leasePath(dir), sealMapFile(kIdLeaseMagic, kIdLeaseVersion, payload),
                             error);
}

std::optional<IdLease> readIdLease(const std::string& dir, std::string* error) {
  if (error != nullptr) error->clear();
  const std::string path = leasePath(dir);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return std::nullopt;
  const std::optional<MapFile> file =
      readMapFile(path, kIdLeaseMagic, kIdLeaseVersion, "id lease", error);
  if (!file) return std::nullopt;
  persistence_detail::ByteReader r(file->payload);
  IdLease lease;
  r.i32(&lease.map_epoch);
  r.i64(&lease.keyframe_floor);
  r.u64(&lease.landmark_floor);
  if (!r.ok() || r.remaining() != 0 || lease.map_epoch < 0 || lease.keyframe_floor < 0) {
    if (error != nullptr) *error = path + ": not a valid id lease";
    return std::nullopt;
  }
  return lease;
}

}  // namespace cblox
