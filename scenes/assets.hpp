// Non-procedural meshes: small files (OBJ, PLY, glTF) under scenes/assets/ or
// named by the scenario, loaded through assimp.
#pragma once

#include <string>

#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

/// Loads every triangle of a mesh file (OBJ, PLY, glTF/GLB) into one mesh:
/// node transforms applied, polygons triangulated, normals generated where the
/// file has none, texture coordinates kept when present (else 0). Coordinates
/// are taken as given (metres, world NED for scene.extra_assets). The mesh is
/// named after the file, with the default material (no texture).
/// Throws UserError naming the file and assimp's message when the file is
/// missing, unreadable or corrupt, or holds no triangles.
sim::Mesh load_mesh_asset(const std::string& path);

/// Folder of the assets shipped with driftlab, the first that exists of: the environment's
/// DRIFTLAB_ASSET_DIR (taken as given), PREFIX/share/driftlab/assets beside the running
/// program's PREFIX/bin (an installed driftlab), the source tree's scenes/assets, and the
/// configured install prefix's share/driftlab/assets (a user's program linked against the
/// installed libraries).
std::string shipped_asset_dir();

/// What an error about a missing shipped asset adds: where they are looked for.
std::string shipped_asset_hint();

/// Path of a shipped asset, e.g. shipped_asset("bollard.obj").
std::string shipped_asset(const std::string& file_name);

}  // namespace driftlab::scenes
