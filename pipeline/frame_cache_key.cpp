#include "pipeline/frame_cache_key.hpp"

#include <fmt/format.h>

#include <cstring>
#include <opencv2/core/utility.hpp>
#include <string_view>

#include "core/hash.hpp"
#include "core/yaml_io.hpp"
#include "sim/physics/waves/ripple_spectrum.hpp"

namespace driftlab::pipeline {
namespace {

// FNV-1a 64 over values fed one by one (their bytes as they lie in memory: doubles and floats
// hash bit for bit, so -0 and 0 differ, as they may in a frame).
class Fingerprint {
 public:
  template <class T>
  void add(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    h_ = fnv1a64(std::string_view(reinterpret_cast<const char*>(&value), sizeof(T)), h_);
  }
  template <class T>
  void add_all(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>);
    add(values.size());
    h_ = fnv1a64(
        std::string_view(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)),
        h_);
  }
  void add(const std::string& text) {
    add(text.size());
    h_ = fnv1a64(text, h_);
  }
  std::string hex() const { return hex64(h_); }

 private:
  std::uint64_t h_ = fnv1a64("");
};

// The scenario's YAML without what decides no frame: its name and description, and the
// sections `pipeline` and `eval` but for pipeline.max_frames. The sections are cut from the text
// rather than put back to their defaults, so that a VO option added or a default changed (code
// outside the renderer's identity) keeps the cached frames. A section added to Scenario later is
// in the key until it is named here (a needless miss, never a stale frame).
std::string frame_deciding_yaml(const Scenario& sc) {
  Scenario s = sc;
  s.name = Scenario{}.name;
  s.description.clear();
  const std::string full = yaml::to_yaml(s, false);
  std::string out;
  bool skipping = false;
  for (std::size_t begin = 0; begin < full.size();) {
    const std::size_t end = std::min(full.find('\n', begin), full.size());
    const std::string_view line(full.data() + begin, end - begin);
    if (!line.empty() && line[0] != ' ' && line[0] != '-')  // a top-level key
      skipping = line.starts_with("pipeline:") || line.starts_with("eval:");
    if (!skipping) {
      out.append(line);
      out += '\n';
    }
    begin = end + 1;
  }
  return out + fmt::format("pipeline:\n  max_frames: {}\n", sc.pipeline.max_frames);
}

}  // namespace

std::string renderer_identity(const std::string& gl_context) {
  return fmt::format("code {}\nopencv {}\nfft {}\ngl {}\n", renderer_code_identity(),
                     cv::getVersionString(), sim::fft_library_version(), gl_context);
}

std::string scene_fingerprint(const sim::SceneGeometry& scene) {
  static_assert(sizeof(sim::Vertex) == 8 * sizeof(float), "Vertex has padding: hash its fields");
  Fingerprint f;
  f.add(scene.meshes.size());
  for (const sim::Mesh& m : scene.meshes) {
    f.add(m.name);
    f.add_all(m.vertices);
    f.add_all(m.indices);
    f.add(m.material.texture);
    f.add(m.material.albedo);
    f.add(m.material.specular);
    f.add(m.material.double_sided);
    f.add(m.mover);
    f.add_all(m.sway);  // std::array<float, 2>: no padding
  }
  f.add(scene.movers.size());
  for (const sim::MoverMotion& v : scene.movers) {
    for (int i = 0; i < 3; ++i) f.add(v.p0_W[i]);
    for (int i = 0; i < 3; ++i) f.add(v.v_W[i]);
    f.add(v.heading_rad);
    for (const sim::Oscillation* o : {&v.roll, &v.pitch, &v.heave})
      for (const double x : {o->amplitude, o->period_s, o->phase_rad}) f.add(x);
  }
  const auto add_texture = [&f](const sim::Texture& t) {
    f.add(t.name);
    f.add(t.width);
    f.add(t.height);
    f.add_all(t.pixels);
    f.add_all(t.alpha);  // which texels are drawn (an alpha-tested texture)
  };
  f.add(scene.textures.size());
  for (const sim::Texture& t : scene.textures) add_texture(t);
  add_texture(scene.sky_clouds);
  const sim::Lighting& l = scene.lighting;
  for (const float v :
       {l.sun ? 1.f : 0.f, l.sun_direction_W.x(), l.sun_direction_W.y(), l.sun_direction_W.z(),
        l.ambient, l.diffuse, l.sky_brightness, l.fog_distance_m, l.sky_zenith_ratio, l.sky_knee,
        l.cloud_contrast, l.cloud_height_over_tile, l.cloud_height_over_visibility})
    f.add(v);
  const sim::WaterAppearance& w = scene.water;
  for (const float v :
       {w.enabled ? 1.f : 0.f, w.extent_m, w.body_gray, w.turbidity, w.reflectivity})
    f.add(v);
  return f.hex();
}

std::string truth_fingerprint(const std::vector<FrameTruth>& truth,
                              const std::vector<sim::SampleTime>& stamps) {
  Fingerprint f;
  f.add(truth.size());
  for (const FrameTruth& t : truth) {
    f.add(t.t_s);
    const Quat& q = t.T_W_B.quaternion();
    const Vec3& p = t.T_W_B.translation();
    for (const double v : {q.w(), q.x(), q.y(), q.z(), p.x(), p.y(), p.z()}) f.add(v);
    for (int i = 0; i < 6; ++i) f.add(t.twist_B[i]);
  }
  f.add(stamps.size());
  for (const sim::SampleTime& s : stamps) {
    f.add(s.t_true_ns);
    f.add(s.t_stamp_ns);
    f.add(s.dropped);
  }
  return f.hex();
}

std::string frame_cache_key(const std::string& identity, const Scenario& sc,
                            const sim::SceneGeometry& scene, const std::vector<FrameTruth>& truth,
                            const std::vector<sim::SampleTime>& stamps) {
  return fmt::format(
      "driftlab frame cache key, version 4\n{}scene_fnv1a64 {}\ntruth_fnv1a64 {}\n"
      "frames {}\n{}",
      identity, scene_fingerprint(scene), truth_fingerprint(truth, stamps), truth.size(),
      frame_deciding_yaml(sc));
}

}  // namespace driftlab::pipeline
