#pragma once

// The mesh stream's LCM messages (mesh_update_t, subvolume_list_t) <-> its core types
// (core/mapping/mesh_update.h): the mapper encodes, cblox-viewer and tests decode.

#include <string>

#include <cblox/mesh_update_t.hpp>
#include <cblox/subvolume_list_t.hpp>

#include "core/mapping/mesh_update.h"

namespace cblox {

/// `update` as a message stamped `utime`. Thread-safe (pure).
mesh_update_t encodeMeshUpdate(const MeshUpdate& update, int64_t utime);
/// The update a message carries. False with a message naming the field when a count
/// disagrees with its array, a number is out of range (negative counts, block indices outside
/// the packable range, more than QuantizedBlockMesh::kMaxVertices vertices) or a block breaks
/// QuantizedBlockMesh::validate(); *update is then unspecified. Thread-safe (pure).
bool decodeMeshUpdate(const mesh_update_t& msg, MeshUpdate* update, std::string* error);

/// `list` as a message stamped `utime`. Thread-safe (pure).
subvolume_list_t encodeSubvolumeList(const SubvolumeList& list, int64_t utime);
/// The list a message carries. False with a message naming the field when a count disagrees
/// with its arrays or a pose or bound is not finite (fromPoseMsg's rules). Thread-safe (pure).
bool decodeSubvolumeList(const subvolume_list_t& msg, SubvolumeList* list, std::string* error);

}  // namespace cblox
