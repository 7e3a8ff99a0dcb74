// Off-screen stereo renderer: draws a SceneGeometry and the wave-displaced
// water surface from the left and right cameras of a rectified stereo rig,
// 8-bit grayscale, with optional per-pixel ground-truth depth.
//
// The projection is built from fx, fy, cx, cy, width and height so that a 3D
// point lands exactly on the pixel the pinhole model gives, in OpenCV's
// pixel-centre convention (pixel (0, 0) is centred on coordinate (0, 0)).
// Rendering uses the world NED frame directly; the camera frame is OpenCV's
// optical frame (x right, y down, z forward).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "sim/physics/waves/ripple_spectrum.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/physics/wind/gusts.hpp"
#include "sim/render/gl_context.hpp"
#include "sim/render/render_options.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::sim {

struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // row-major, row 0 at the top
  std::uint8_t at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
};

struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth_m;  // optical-axis depth z [m]; 0 where no surface (sky)
  float at(int x, int y) const { return depth_m[static_cast<std::size_t>(y) * width + x]; }
};

struct StereoImages {
  GrayImage left, right;
  DepthImage depth_left;  // empty unless ground-truth depth was requested
  GrayImage moving_left;  // the moving things' mask (TruthImages::moving); empty unless asked for
};

/// The left camera's ground truth at one instant: the depth, and the mask of the moving things
/// (255 where the surface seen belongs to a mover, Mesh::mover; 0 elsewhere: the static scene,
/// the water, the sky). Single-sampled, one sample a pixel at its centre; a mover's mirror
/// image in the water is not in the mask (the pixel shows the water).
struct TruthImages {
  DepthImage depth;
  GrayImage moving;
};

/// Clip-space projection (column-vector convention, OpenGL NDC) of the
/// pinhole camera: x_ndc = (2 (u + 0.5) / width) - 1 with u = fx x / z + cx,
/// y_ndc likewise with rows growing downwards (window row = image row).
Eigen::Matrix4f projection_from_intrinsics(const PinholeCamera& camera, float near_m, float far_m);

/// A band of image rows drawn from one pose at one time: a rolling shutter's
/// rows exposed together, or the whole image (rows [0, height)).
struct RowBand {
  SE3 T_W_C;  // the LEFT camera's pose (world NED <- optical); the right eye adds the rig
  double t_s = 0;
  int row_begin = 0;
  int row_end = 0;  // one past the last row
};

/// An 8-bit colour image, row-major, blue, green, red per pixel (OpenCV's order).
struct ColourImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> bgr;
};

/// What a renderer's eyes hold: gray (the stereo cameras) or colour (materials tinted by
/// Material::colour; water, sky and the mirror image stay gray).
enum class ImageKind { kGray, kColour };

/// Where a renderer's time goes (StereoRenderer::set_profiling): the wall time of each pass,
/// summed over every call since profiling began, with glFinish after each pass, so that the
/// passes do not overlap as they do unprofiled (their sum exceeds an unprofiled frame's time).
/// describe_passes turns it into text.
struct RenderPassTimes {
  int renders = 0;            ///< render() and render_bands() calls (stereo pairs drawn)
  int truths = 0;             ///< render_truth() calls
  double mirror_ms = 0;       ///< the mirror images: the scene and the sky mirrored
  double mirror_mips_ms = 0;  ///< their blur levels (only under wind ripples)
  double ripples_ms = 0;      ///< the ripples' slope maps: baked and uploaded once a time step
  double water_ms = 0;        ///< the water surface, sampling the mirror image
  double scene_ms = 0;        ///< the scene's meshes (banks, trees, buildings, vessels)
  double sky_ms = 0;          ///< the sky where nothing else was drawn
  double readback_ms = 0;     ///< both eyes resolved and read back to the CPU
  double truth_ms = 0;        ///< render_truth: depth and the moving mask, read back
  double total_ms() const;
};
/// One line a pass: its mean milliseconds a stereo pair (truth: a call) and its share.
std::string describe_passes(const RenderPassTimes& t);

/// Largest number of wave components the water shader sums (the strongest are kept).
constexpr int kMaxShaderWaveComponents = 32;

class StereoRenderer {
 public:
  /// Creates the GL context of `options.backend`. Throws UserError for an
  /// invalid rig (naming the field) or an unavailable backend.
  StereoRenderer(const StereoRig& rig, const RenderOptions& options,
                 ImageKind kind = ImageKind::kGray);
  ~StereoRenderer();
  StereoRenderer(const StereoRenderer&) = delete;
  StereoRenderer& operator=(const StereoRenderer&) = delete;

  /// Uploads meshes and textures (replacing any earlier scene).
  void upload(const SceneGeometry& scene);
  /// The wave components the water surface shows (calm when empty).
  void set_waves(const std::vector<WaveComponent>& components);
  /// The wind ripples that break the mirror image up (sim::RippleMaps, baked
  /// at each frame's time and shared by both eyes): drawn in the shading only,
  /// not in the geometry or the depth (none when null or empty, the default).
  void set_ripples(std::shared_ptr<RippleMaps> maps);
  /// How the wind moves the meshes with sway weights (Mesh::sway): drawn in every pass at
  /// its instant, and in render_truth's mask (still when empty, the default).
  void set_sway(const VegetationSway& sway);
  /// Where the body meshes (Mesh::on_body) are drawn: the body (FRD) frame's pose in the
  /// world (NED). The identity until set.
  void set_body_pose(const SE3& T_W_B);
  /// Where the right camera really is relative to the left (a miscalibrated
  /// rig: see sim::true_T_left_right); the rig's nominal baseline by default.
  void set_right_camera(const SE3& T_left_right);
  /// Renders the pair at left-camera pose T_W_C (world NED <- optical) and time t_s.
  StereoImages render(const SE3& T_W_C_left, double t_s, bool with_depth);
  /// Renders each eye band by band (bands in row order, together covering every row once),
  /// each band's rows from its own pose and time; the right eye's bands give the left
  /// camera's pose at the right image's times. Without depth. With `moving_mask`, also
  /// the left image's moving things in moving_left, written by the left eye's own pass (the
  /// scene shader's flag in a second channel): render_truth's mask at the band's pose and time
  /// without its pass. Needs one left band, a gray renderer and no multisampling.
  StereoImages render_bands(const std::vector<RowBand>& left, const std::vector<RowBand>& right,
                            bool moving_mask = false);

  /// The left camera's depth and moving-things mask at pose T_W_C and time t_s, in one pass
  /// (render(..., true)'s depth is this pass's).
  TruthImages render_truth(const SE3& T_W_C, double t_s);
  /// Whether anything of the uploaded scene moves: movers (SceneGeometry::movers), or meshes
  /// with sway weights while set_sway's wind blows.
  bool has_moving_things() const;

  /// Renders the left eye only, in colour, at pose T_W_C and time t_s (a renderer made with
  /// ImageKind::kColour; InternalError otherwise).
  ColourImage render_colour(const SE3& T_W_C, double t_s);
  const std::string& context_description() const;
  std::size_t triangles() const;
  /// Where the eye pass draws the water beside the scene: it changes the cost, never the bytes
  /// (a pixel where the water meets a surface at the same depth shows the water in both
  /// orders). By cost, the default: after the scene when ripples make its shader the costliest
  /// (llvmpipe then skips it behind the banks), before it when calm (it hides the banks below
  /// it). The other two for tests that compare the orders.
  enum class WaterOrder { kByCost, kFirst, kLast };
  void set_water_order(WaterOrder order);
  /// Whether each mesh's runs of triangles that cannot be in a pass's view are skipped (true,
  /// the default): it changes the cost, never the bytes (a triangle outside the view draws no
  /// pixel, and those drawn keep their order). False for tests that compare.
  void set_run_culling(bool on);
  /// The triangles sent to OpenGL since the renderer was made, all passes together.
  std::size_t triangles_submitted() const;
  /// Times each pass from now on (glFinish after each: slower, the same images) into
  /// pass_times(), reset here; false stops.
  void set_profiling(bool on);
  const RenderPassTimes& pass_times() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace driftlab::sim
