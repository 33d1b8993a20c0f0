#include "core/mapping/output_path.h"

namespace cblox {

std::optional<std::filesystem::path> resolveOutputPath(const std::filesystem::path& output_dir,
                                                       const std::string& requested,
                                                       std::string* error) {
  auto fail = [&](const std::string& why) -> std::optional<std::filesystem::path> {
    if (error != nullptr) *error = "path '" + requested + "' " + why;
    return std::nullopt;
  };
  if (requested.empty()) return fail("is empty");
  if (requested.find('\0') != std::string::npos) return fail("contains a NUL character");
  const std::filesystem::path path(requested);
  for (const auto& part : path) {
    if (part == "..") return fail("contains '..'");
  }
  const std::filesystem::path base = output_dir.lexically_normal();
  if (path.is_absolute()) {
    const std::filesystem::path normal = path.lexically_normal();
    const std::filesystem::path relative = normal.lexically_relative(base);
    if (relative.empty() || *relative.begin() == "..") {
      return fail("is outside the output directory " + base.string());
    }
    return normal;
  }
  return (base / path).lexically_normal();
}

bool staysInsideOnDisk(const std::filesystem::path& output_dir,
                       const std::filesystem::path& target, std::string* error) {
  std::error_code ec;
  const std::filesystem::path base = std::filesystem::canonical(output_dir, ec);
  if (ec) {
    if (error != nullptr) *error = "output directory " + output_dir.string() + ": " + ec.message();
    return false;
  }
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(target, ec);
  if (ec) {
    if (error != nullptr) *error = "path " + target.string() + ": " + ec.message();
    return false;
  }
  const std::filesystem::path relative = resolved.lexically_relative(base);
  if (relative.empty() || *relative.begin() == "..") {
    if (error != nullptr) {
      *error = "path '" + target.string() + "' leads outside the output directory " +
               base.string() + " (through a symbolic link, to " + resolved.string() + ")";
    }
    return false;
  }
  return true;
}

std::optional<std::filesystem::path> writableOutputPath(const std::filesystem::path& output_dir,
                                                        const std::string& requested,
                                                        std::string* error) {
  std::optional<std::filesystem::path> path = resolveOutputPath(output_dir, requested, error);
  if (!path || !staysInsideOnDisk(output_dir, *path, error)) return std::nullopt;
  return path;
}

}  // namespace cblox
