#pragma once

#include <string>
#include <string_view>

namespace cblox {

/// Replaces the file at `path` with `data` atomically and durably: the bytes go to a temporary
/// file "<path>.tmp.<pid>.<n>" in the same directory (n counts the calls of this process), which
/// is fsync'ed, renamed over `path`, and then the directory is fsync'ed. A reader (or a crash
/// at any point) sees either the complete old file or the complete new one, never a mix;
/// after a crash a leftover temporary file may remain (readers ignore "*.tmp.*" files). The
/// new file has mode 0644 (minus the umask). Returns false, with "<path>: <step> failed:
/// <errno text>" in *error (if non-null), when any step fails; the temporary file is removed
/// then and `path` is left as it was (its old content, or absent), except when only the final
/// directory fsync fails (the new file is in place then, but not known to be durable). The
/// directory must exist.
/// Thread-safe (no shared state but an atomic counter); concurrent writers of the same path
/// each produce a complete file, the last rename wins.
bool writeFileAtomically(const std::string& path, std::string_view data, std::string* error);

/// fsync()s the directory `dir`, making renames and creations of its entries durable. Returns
/// false with "<dir>: fsync of the directory failed: <errno text>" (or "open ... failed") in
/// *error (if non-null). Thread-safe (no shared state).
bool syncDirectory(const std::string& dir, std::string* error);

}  // namespace cblox
