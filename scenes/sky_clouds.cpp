#include "scenes/sky_clouds.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "scenes/noise.hpp"

namespace driftlab::scenes {

sim::Texture bake_cloud_layer(std::uint64_t seed, int size) {
  DRIFTLAB_DEMAND_MSG(size >= 64 && size <= 4096, "bake_cloud_layer: size outside [64, 4096]");
  Rng rng = RngStreams(seed).stream("scene.sky.clouds");
  const Noise noise = Noise::from(rng);
  const double gain = std::exp2(-1.0 / 3.0);
  std::vector<double> n(static_cast<std::size_t>(size) * size);
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c)
      n[static_cast<std::size_t>(r) * size + c] =
          noise.fbm((c + 0.5) / size, (r + 0.5) / size, 4, 4, 5, gain);
  double sum = 0, sum2 = 0;
  for (double v : n) sum += v;
  const double mean = sum / static_cast<double>(n.size());
  for (double v : n) sum2 += (v - mean) * (v - mean);
  const double sd = std::sqrt(sum2 / static_cast<double>(n.size()));
  sim::Texture t;
  t.name = "sky_clouds";
  t.width = t.height = size;
  t.pixels.resize(n.size());
  for (std::size_t i = 0; i < n.size(); ++i)
    t.pixels[i] = static_cast<std::uint8_t>(
        std::clamp(std::lround(128.0 + 32.0 * (n[i] - mean) / sd), 0L, 255L));
  return t;
}

}  // namespace driftlab::scenes
