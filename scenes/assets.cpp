#include "scenes/assets.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/core.h>
#include <assimp/Importer.hpp>

#include "core/error.hpp"

// The build points these at the source tree's scenes/assets and at the install prefix's
// share/driftlab/assets; without them, the path is relative to the working directory.
#ifndef DRIFTLAB_SCENES_ASSET_DIR
#define DRIFTLAB_SCENES_ASSET_DIR "scenes/assets"
#endif
#ifndef DRIFTLAB_INSTALLED_ASSET_DIR
#define DRIFTLAB_INSTALLED_ASSET_DIR ""
#endif

namespace driftlab::scenes {

namespace {

bool is_dir(const std::filesystem::path& p) {
  std::error_code ec;
  return !p.empty() && std::filesystem::is_directory(p, ec);
}

}  // namespace

std::string shipped_asset_dir() {
  if (const char* env = std::getenv("DRIFTLAB_ASSET_DIR"); env && *env) return env;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  // An installed program: PREFIX/bin/driftlab next to PREFIX/share/driftlab/assets.
  if (!ec && is_dir(exe.parent_path().parent_path() / "share/driftlab/assets"))
    return (exe.parent_path().parent_path() / "share/driftlab/assets").string();
  if (is_dir(DRIFTLAB_SCENES_ASSET_DIR)) return DRIFTLAB_SCENES_ASSET_DIR;
  if (is_dir(DRIFTLAB_INSTALLED_ASSET_DIR)) return DRIFTLAB_INSTALLED_ASSET_DIR;
  return DRIFTLAB_SCENES_ASSET_DIR;  // missing: the error names it
}

std::string shipped_asset_hint() {
  return "; driftlab's own assets are looked for in $DRIFTLAB_ASSET_DIR, "
         "PREFIX/share/driftlab/assets beside PREFIX/bin/driftlab, and the source tree's "
         "scenes/assets";
}

std::string shipped_asset(const std::string& file_name) {
  return (std::filesystem::path(shipped_asset_dir()) / file_name).string();
}

sim::Mesh load_mesh_asset(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw UserError(
        fmt::format("mesh asset '{}': no such file (expected an OBJ, PLY or glTF file){}", path,
                    path.starts_with(shipped_asset_dir()) ? shipped_asset_hint() : ""));

  Assimp::Importer importer;
  // Hard edges (a bollard's rim, a box corner) keep separate normals.
  importer.SetPropertyFloat(AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, 60.0f);
  // Points and lines are not drawable surfaces; drop them.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_GenSmoothNormals |
                         aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                         aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  const aiScene* scene = importer.ReadFile(path, flags);
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0)
    throw UserError(fmt::format("mesh asset '{}': cannot be read as a mesh: {}", path,
                                importer.GetErrorString()));

  sim::Mesh out;
  out.name = path;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    if ((mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
    if (out.vertices.size() + mesh->mNumVertices > std::numeric_limits<std::uint32_t>::max())
      throw UserError(fmt::format("mesh asset '{}': too many vertices", path));
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D& p = mesh->mVertices[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw UserError(fmt::format("mesh asset '{}': vertex {} is not finite", path, i));
      aiVector3D n = mesh->HasNormals() ? mesh->mNormals[i] : aiVector3D(0, 0, 0);
      const float len = n.Length();
      // Degenerate faces give zero or NaN normals; any unit vector is then as
      // good as another, and the renderer needs a unit one.
      n = (std::isfinite(len) && len > 1e-6f) ? n / len : aiVector3D(0, 0, -1);
      const bool uv = mesh->HasTextureCoords(0);
      out.vertices.push_back({p.x, p.y, p.z, n.x, n.y, n.z, uv ? mesh->mTextureCoords[0][i].x : 0.f,
                              uv ? mesh->mTextureCoords[0][i].y : 0.f});
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (unsigned k = 0; k < 3; ++k) out.indices.push_back(base + face.mIndices[k]);
    }
  }
  if (out.indices.empty())
    throw UserError(fmt::format("mesh asset '{}': contains no triangles", path));
  return out;
}

}  // namespace driftlab::scenes
