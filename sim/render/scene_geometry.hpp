// What the renderer draws: triangle meshes in the world frame (NED, metres)
// with grayscale textures, plus the water surface and the sky. The scenes
// module builds one of these from the scenario; the renderer uploads it once.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/rotation.hpp"
#include "core/se3.hpp"

namespace driftlab::sim {

/// One vertex: world position (NED) [m], unit normal (NED), texture coordinates.
struct Vertex {
  float x, y, z;
  float nx, ny, nz;
  float u, v;
};

/// A grayscale texture (row-major, `width` x `height`, 8 bits), repeated
/// (wrapped) when texture coordinates leave [0, 1].
struct Texture {
  std::string name;
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
  // Empty: opaque. Otherwise width x height coverages (row-major, as pixels): a mesh whose
  // material's texture has alpha is alpha-tested (a texel is drawn where its filtered alpha is
  // at least kAlphaOpaqueFrom / 255, never blended), in colour, depth and the mirror pass alike;
  // its mip levels keep the coverage of level 0 (sim/render/alpha_mips.hpp). Leaf-cluster cards.
  std::vector<std::uint8_t> alpha;
};

/// The alpha (0-255) from which a texel of an alpha-tested texture is drawn (0.5 after filtering).
inline constexpr std::uint8_t kAlphaOpaqueFrom = 128;

/// How a mesh reflects light.
struct Material {
  int texture = -1;       // index into SceneGeometry::textures, -1 = none (white)
  float albedo = 0.6f;    // multiplies the texture [0, 1]
  float specular = 0.0f;  // strength of a sun glint on this surface [0, 1]
  // false: the surface is seen only from the side its normals point to (it bounds a solid: a
  // closed crown or trunk, or terrain over the ground), so the renderer skips its back faces
  // (as glTF's doubleSided). Its triangles must be wound counter-clockwise about their normals
  // ((b - a) x (c - a) along the normal), as MeshBuilder's are. true: open sheets seen from both
  // sides (reed blades, sheet piling, roofs seen from below).
  bool double_sided = true;
  // Reflectance by colour channel (linear R, G, B), multiplying the gray shading in colour
  // images (StereoRenderer's ImageKind::kColour: the basin's overhead camera and its
  // markers); gray images ignore it.
  std::array<float, 3> colour{1.0f, 1.0f, 1.0f};
};

/// A sinusoid a sin(2 pi t / T + phase): one degree of freedom of a rocking object.
struct Oscillation {
  double amplitude = 0;  // [rad] or [m]
  double period_s = 1;
  double phase_rad = 0;
  double at(double t_s) const {
    return amplitude * std::sin(2 * std::numbers::pi * t_s / period_s + phase_rad);
  }
};

/// How a moving object of the scene (a mover: another vessel) moves, in closed form so that
/// every instant a renderer draws (a rolling shutter's band, a motion blur's sample, the
/// reflection pass) has its exact pose: its origin runs at a constant velocity and heaves, and
/// it rolls and pitches about its mean attitude, T_W_M(t) = (Rz(heading) Ry(pitch(t))
/// Rx(roll(t)), p0 + v t + heave(t) e_down).
struct MoverMotion {
  Eigen::Vector3d p0_W = Eigen::Vector3d::Zero();  // origin at t = 0 (NED) [m]
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();   // velocity (NED) [m/s]
  double heading_rad = 0;
  Oscillation roll, pitch;  // [rad]
  Oscillation heave;        // [m], down positive
  SE3 T_W_M(double t_s) const {
    const Quat q = quat_from_euler_zyx({roll.at(t_s), pitch.at(t_s), heading_rad});
    return SE3(q, p0_W + v_W * t_s + Eigen::Vector3d(0, 0, heave.at(t_s)));
  }
};

struct Mesh {
  std::string name;
  // false: vertices in the world frame (NED), fixed. true: in the vessel's body frame (FRD),
  // drawn at the pose StereoRenderer::set_body_pose gives (the ship model seen from the
  // basin's overhead camera).
  bool on_body = false;
  // -1: not moving. Otherwise an index into SceneGeometry::movers: the vertices are in that
  // mover's frame, drawn at its pose at each instant, and its pixels are the moving things of
  // StereoRenderer::render_truth's mask.
  int mover = -1;
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;  // triangles, 3 per face
  Material material;
  // Empty: rigid. Otherwise one per vertex: how far it sways in the wind's gusts, as a share of
  // the top of a sim::kReferenceTreeHeight_m tree (sim::VegetationSway::sway_m), and how far it
  // flutters (1 for a leaf card). StereoRenderer::set_sway says how the wind moves them.
  std::vector<std::array<float, 2>> sway;
};

/// The sway weights of `dst` after src's vertices were appended to it from index `base` on
/// (mesh merging): a rigid mesh's vertices weigh 0, and the merge stays rigid (no weights) while
/// both parts are.
inline void append_sway(Mesh* dst, std::size_t base, const Mesh& src) {
  if (src.sway.empty() && dst->sway.empty()) return;
  dst->sway.resize(base, {0.f, 0.f});
  if (src.sway.empty())
    dst->sway.resize(dst->vertices.size(), {0.f, 0.f});
  else
    dst->sway.insert(dst->sway.end(), src.sway.begin(), src.sway.end());
}

/// Light and sky.
struct Lighting {
  bool sun = false;                                    // false: overcast
  Eigen::Vector3f sun_direction_W{0.3f, 0.2f, -0.9f};  // towards the sun (NED, z up is negative)
  float ambient = 0.55f;                               // overcast sky light [0, 1]
  float diffuse = 0.45f;                               // directional part
  float sky_brightness = 0.85f;                        // sky gray level at the horizon [0, 1]
  float fog_distance_m = 400.f;                        // distance at which fog reaches 63% [m]
  // The sky's luminance by elevation e: L_h (1 + (r - 1) sin e), r = L(zenith) / L(horizon).
  // r = 3 is the CIE overcast sky (Moon and Spencer 1942, CIE standard sky 1); 1 a uniform sky.
  float sky_zenith_ratio = 1.12f;
  // The camera's highlight shoulder on the sky: luminance above the knee k is compressed as
  // k + (1 - k)(1 - exp(-(L - k)/(1 - k))), so a bright overcast sky keeps its gradient and
  // clouds below white. >= 1: plain clipping at 1. sky_brightness is the horizon's grey after
  // the shoulder (the fog's colour), the renderer finds the luminance that gives it.
  float sky_knee = 1.0f;
  // The cloud deck (SceneGeometry::sky_clouds): relative rms of the sky's luminance it adds
  // (0: none), its height over the texture's tile (the deck's scale) and over the visibility
  // (its contrast fades as exp(-(H/V) / sin e) along the slant path).
  float cloud_contrast = 0.f;
  float cloud_height_over_tile = 0.0625f;
  float cloud_height_over_visibility = 0.05f;
};

/// The sky's luminance at the horizon before the shoulder (Lighting::sky_knee): the inverse of
/// the shoulder at sky_brightness, L_h = k - (1 - k) ln(1 - (b - k)/(1 - k)) for b > k.
inline double sky_horizon_luminance(const Lighting& l) {
  const double k = l.sky_knee, b = std::min(static_cast<double>(l.sky_brightness), 0.999);
  if (k >= 1.0 || b <= k) return l.sky_brightness;
  return k - (1.0 - k) * std::log(1.0 - (b - k) / (1.0 - k));
}

/// The water surface: a plane at still-water level (z = 0) displaced by the
/// wave field, with reflection and a body colour.
struct WaterAppearance {
  bool enabled = true;
  float extent_m = 300.f;     // half-size of the water grid around the camera [m]
  float body_gray = 0.18f;    // colour of light coming up from the water body [0, 1]
  float turbidity = 0.5f;     // 0 clear (dark) .. 1 murky (brighter, less reflective)
  float reflectivity = 1.0f;  // scales the Fresnel reflectance
};

struct SceneGeometry {
  std::vector<Mesh> meshes;
  std::vector<Texture> textures;
  Lighting lighting;
  WaterAppearance water;
  // The cloud deck's texture: unit-variance noise n stored as 128 + 32 n, tiling (empty: none).
  Texture sky_clouds;
  // The moving objects (Mesh::mover indexes them).
  std::vector<MoverMotion> movers;

  std::size_t triangle_count() const {
    std::size_t n = 0;
    for (const auto& m : meshes) n += m.indices.size() / 3;
    return n;
  }
};

}  // namespace driftlab::sim
