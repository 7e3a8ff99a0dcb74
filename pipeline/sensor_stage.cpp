#include "pipeline/sensor_stage.hpp"

#include <algorithm>
#include <cmath>

#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "scenes/sky_obstruction.hpp"

namespace driftlab::pipeline {

namespace {

// Is t the next of `times` (advancing the cursor)?
bool take(const std::vector<TimeNs>& times, std::size_t* next, TimeNs t) {
  while (*next < times.size() && times[*next] < t) ++*next;
  if (*next < times.size() && times[*next] == t) {
    ++*next;
    return true;
  }
  return false;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Frees a vector's storage (clear() keeps it).
template <class T>
void release(std::vector<T>* v) {
  std::vector<T>().swap(*v);
}

}  // namespace

struct SensorStage::Impl {
  Scenario sc;
  std::filesystem::path dir;
  RngStreams rng;
  std::unique_ptr<sim::ImuSimulator> imu;
  std::unique_ptr<sim::ImuCsvWriter> imu_csv;
  std::unique_ptr<sim::AhrsSimulator> ahrs;
  std::unique_ptr<sim::AhrsCsvWriter> ahrs_csv;
  std::vector<TimeNs> imu_times, gps_times, compass_times, ahrs_times;
  std::size_t imu_next = 0, gps_next = 0, compass_next = 0, ahrs_next = 0;
  std::vector<sim::BodySample> gps_bodies, compass_bodies;
  std::vector<std::pair<TimeNs, ImuBias>> imu_biases;  // after each IMU sample, dropped ones too
  SensorData data;

  Impl(const Scenario& s, const std::filesystem::path& d) : sc(s), dir(d), rng(s.seed) {
    if (sc.sensors.imu.enabled) {
      imu = std::make_unique<sim::ImuSimulator>(sc.sensors.imu, rng, "imu");
      imu_csv = std::make_unique<sim::ImuCsvWriter>(dir / "imu.csv");
    }
    if (sc.sensors.ahrs.enabled) {
      ahrs = std::make_unique<sim::AhrsSimulator>(
          sc.sensors.ahrs, sim::earth_field_ned_nt(sc.sensors.compass), rng, "ahrs");
      ahrs_csv = std::make_unique<sim::AhrsCsvWriter>(dir / "ahrs.csv");
    }
  }
};

SensorStage::SensorStage(const Scenario& sc, const std::filesystem::path& dir)
    : impl_(std::make_unique<Impl>(sc, dir)) {}

SensorStage::~SensorStage() = default;

std::vector<TimeNs> SensorStage::sample_times(double end_s) const {
  Impl& s = *impl_;
  const auto& o = s.sc.sensors;
  s.imu_times = o.imu.enabled ? sim::sample_times(o.imu.rate_hz, end_s) : std::vector<TimeNs>{};
  s.gps_times = o.gps.enabled ? sim::sample_times(o.gps.rate_hz, end_s) : std::vector<TimeNs>{};
  s.compass_times =
      o.compass.enabled ? sim::sample_times(o.compass.rate_hz, end_s) : std::vector<TimeNs>{};
  s.ahrs_times =
      o.ahrs.enabled ? sim::sample_times(o.ahrs.update_rate_hz, end_s) : std::vector<TimeNs>{};
  std::vector<TimeNs> all;
  all.reserve(s.imu_times.size() + s.gps_times.size() + s.compass_times.size() +
              s.ahrs_times.size());
  all.insert(all.end(), s.imu_times.begin(), s.imu_times.end());
  all.insert(all.end(), s.gps_times.begin(), s.gps_times.end());
  all.insert(all.end(), s.compass_times.begin(), s.compass_times.end());
  all.insert(all.end(), s.ahrs_times.begin(), s.ahrs_times.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

void SensorStage::on_sample(const sim::BodySample& b) {
  Impl& s = *impl_;
  if (s.imu && take(s.imu_times, &s.imu_next, b.t_ns)) {
    if (const auto m = s.imu->measure(b)) {
      s.imu_csv->write(*m);
      s.data.imu.push_back(*m);
    }
    s.imu_biases.push_back({b.t_ns, {s.imu->gyro().bias, s.imu->accel().bias}});
  }
  if (s.ahrs && take(s.ahrs_times, &s.ahrs_next, b.t_ns))
    if (const auto a = s.ahrs->update(b)) {
      s.ahrs_csv->write(*a);
      s.data.ahrs.push_back(*a);
    }
  if (take(s.gps_times, &s.gps_next, b.t_ns)) s.gps_bodies.push_back(b);
  if (take(s.compass_times, &s.compass_next, b.t_ns)) s.compass_bodies.push_back(b);
}

std::optional<ImuBias> SensorStage::imu_bias_at(TimeNs t_ns) const {
  const auto& h = impl_->imu_biases;
  if (h.empty()) return std::nullopt;
  auto it = std::upper_bound(h.begin(), h.end(), t_ns,
                             [](TimeNs t, const auto& sample) { return t < sample.first; });
  return it == h.begin() ? h.front().second : std::prev(it)->second;
}

SensorData SensorStage::finish(const sim::SceneGeometry* scene) {
  Impl& s = *impl_;
  record::SensorsRecord& stats = s.data.stats;
  if (s.imu_csv) {
    s.imu_csv->commit();
    stats.imu = record::ImuRecord{s.data.imu.size(), s.sc.sensors.imu.rate_hz};
  }
  // What only the physics stage needed goes before the frame loop: the sample times run to the
  // motion's hard limit (24 MB for the IMU at 200 Hz), and the IMU's samples, grown by
  // doubling, may hold twice their size.
  release(&s.imu_times);
  release(&s.gps_times);
  release(&s.compass_times);
  release(&s.ahrs_times);
  release(&s.imu_biases);
  if (s.ahrs_csv) {
    s.ahrs_csv->commit();
    double sq[3] = {0, 0, 0};
    for (const sim::AhrsSample& a : s.data.ahrs) {
      sq[0] += std::pow(wrap_angle_rad(a.euler.roll_rad - a.true_euler.roll_rad), 2);
      sq[1] += std::pow(wrap_angle_rad(a.euler.pitch_rad - a.true_euler.pitch_rad), 2);
      sq[2] += std::pow(wrap_angle_rad(a.euler.yaw_rad - a.true_euler.yaw_rad), 2);
    }
    const double n = std::max<double>(1.0, static_cast<double>(s.data.ahrs.size()));
    stats.ahrs = record::AhrsRecord{s.data.ahrs.size(), s.sc.sensors.ahrs.rate_hz,
                                    rad2deg(std::sqrt(sq[0] / n)), rad2deg(std::sqrt(sq[1] / n)),
                                    rad2deg(std::sqrt(sq[2] / n))};
  }
  s.data.imu.shrink_to_fit();
  if (s.sc.sensors.gps.enabled) {
    std::unique_ptr<scenes::MeshSkyObstruction> sky;
    if (scene != nullptr) sky = std::make_unique<scenes::MeshSkyObstruction>(*scene);
    sim::GpsSimulator gps(s.sc.sensors.gps, s.rng, sky.get(), "gps");
    sim::GpsCsvWriter csv(s.dir / "gps.csv");
    std::vector<double> sats, hdop;
    int below = 0, fixes = 0;
    for (const sim::BodySample& b : s.gps_bodies) {
      const auto fix = gps.measure(b);
      if (!fix) continue;
      csv.write(*fix);
      s.data.gps.push_back(*fix);
      sats.push_back(fix->satellites);
      if (fix->satellites < s.sc.sensors.gps.min_satellites) ++below;
      if (fix->fix) {
        ++fixes;
        hdop.push_back(fix->hdop);
      }
    }
    csv.commit();
    double hdop_mean = 0.0;
    for (double h : hdop) hdop_mean += h / static_cast<double>(hdop.size());
    const double n = static_cast<double>(s.data.gps.size());
    stats.gps = record::GpsRecord{s.data.gps.size(),
                                  n > 0 ? fixes / n : 0.0,
                                  n > 0 ? below / n : 0.0,
                                  sats.empty() ? 0.0 : median(sats),
                                  hdop.empty() ? eval::kUnmeasured : hdop_mean,
                                  scene != nullptr ? "scene meshes" : "open"};
  }
  if (s.sc.sensors.compass.enabled) {
    sim::CompassOptions options = s.sc.sensors.compass;
    if (scene != nullptr && options.steel_structures) {
      const auto steel =
          scenes::steel_anomalies(*scene, options.steel_field_ned_nt, options.steel_decay_length_m,
                                  options.steel_decay_exponent);
      options.anomalies.insert(options.anomalies.end(), steel.begin(), steel.end());
    }
    sim::CompassSimulator compass(options, s.rng, "compass");
    sim::CompassCsvWriter csv(s.dir / "compass.csv");
    double sq = 0.0, worst = 0.0;
    for (const sim::BodySample& b : s.compass_bodies) {
      const auto m = compass.measure(b);
      if (!m) continue;
      csv.write(*m);
      s.data.compass.push_back(*m);
      const double e = std::remainder(m->heading_rad - m->true_heading_rad, 2 * M_PI);
      sq += e * e;
      worst = std::max(worst, std::abs(e));
    }
    csv.commit();
    const double n = static_cast<double>(s.data.compass.size());
    stats.compass =
        record::CompassRecord{s.data.compass.size(), options.anomalies.size(),
                              n > 0 ? std::sqrt(sq / n) * 180 / M_PI : 0.0, worst * 180 / M_PI};
  }
  release(&s.gps_bodies);
  release(&s.compass_bodies);
  return std::move(s.data);
}

}  // namespace driftlab::pipeline
