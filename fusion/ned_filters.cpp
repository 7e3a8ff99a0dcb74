#include "fusion/ned_filters.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/rotation.hpp"

namespace driftlab::fusion {

namespace {

template <class O>
const O& validated(const O& options, const char* who) {
  yaml::validate_or_throw(options, who);
  return options;
}

bool finite(const NedVector& x) { return x.allFinite(); }

// The deterministic part of Eq. (2) for one state: position moved by (u, v) rotated by the
// heading at the middle of the step, heading turned by the yaw input.
void propagate_mean(NedVector* x, double dt, double dpsi) {
  const double psi_m = (*x)(ned::kHeading) + 0.5 * dpsi;
  const double c = std::cos(psi_m), s = std::sin(psi_m);
  const double u = (*x)(ned::kSurge), v = (*x)(ned::kSway);
  (*x)(ned::kNorth) += dt * (u * c - v * s);
  (*x)(ned::kEast) += dt * (u * s + v * c);
  (*x)(ned::kHeading) = wrap_angle_rad((*x)(ned::kHeading) + dpsi);
}

// Eqs. (4)-(6) for one measured component j of the state (H = e_j^T, R = r), with the
// innovation given (wrapped for the heading). Eq. (6) in Joseph form, (I - K H) P (I - K H)^T +
// K R K^T, equal to (I - K H) P for the optimal gain and symmetric positive semi-definite under
// rounding. Eq. (5) as printed applies Phi to the prior a second time; the standard update
// x = x^- + K (z - H x^-) is meant.
void scalar_update(NedVector* x, NedMatrix* P, int j, double innovation, double r) {
  const double S = (*P)(j, j) + r;      // H P^- H^T + R
  const NedVector K = P->col(j) / S;    // Eq. (4)
  *x += K * innovation;                 // Eq. (5)
  NedMatrix A = NedMatrix::Identity();  // I - K H
  A.col(j) -= K;
  *P = A * (*P) * A.transpose() + (K * r) * K.transpose();  // Eq. (6)
  *P = 0.5 * (*P + P->transpose());
}

void append_double(std::string* out, double v) {
  *out += ',';
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out->append(buf, r.ptr);
}

}  // namespace

NedVector NedState::vector() const {
  NedVector x;
  x << north_m, east_m, surge_m_s, sway_m_s, heading_rad;
  return x;
}

SE3 NedEstimate::T_W_B() const {
  return SE3(quat_from_euler_zyx({0.0, 0.0, heading_rad()}), Vec3(north_m(), east_m(), 0.0));
}

// ---------------------------------------------------------------------------------------------

NedFilterBase::NedFilterBase(const NedFilterOptions& model, const NedState& initial,
                             const char* who)
    : model_(model), x0_(initial.vector()), who_(who) {
  x0_(ned::kHeading) = wrap_angle_rad(x0_(ned::kHeading));
  if (!model_.compass_noise_rad)
    throw UserError(fmt::format(
        "{}: compass_noise_rad: got null, expected a number (the pipeline fills null from the "
        "scenario's compass)",
        who));
  if (!x0_.allFinite()) {
    throw UserError(fmt::format("{}: the initial state must be finite, got [{}, {}, {}, {}, {}]",
                                who, x0_(0), x0_(1), x0_(2), x0_(3), x0_(4)));
  }
}

NedVector NedFilterBase::prior_variance() const {
  NedVector d;
  const double p = model_.initial_position_sd_m, v = model_.initial_velocity_sd_m_s,
               h = model_.initial_heading_sd_rad;
  d << p * p, p * p, v * v, v * v, h * h;
  return d;
}

void NedFilterBase::reset_clock() {
  started_ = false;
  t_prev_ns_ = 0;
  last_yaw_rate_ = 0.0;
  vo_velocity_noise_.reset();
  vo_yaw_rate_noise_.reset();
}

NedFilterBase::VoNoise NedFilterBase::vo_noise(const BodyVelocityMeasurement& vo) {
  const NedFilterOptions built_in;
  VoNoise n;
  if (model_.vo_increment_noise_m) {
    n.velocity_sd = *model_.vo_increment_noise_m / vo.dt_s;
  } else {
    vo_velocity_noise_.add(0, vo.surge_m_s);
    vo_velocity_noise_.add(1, vo.sway_m_s);
    n.velocity_sd = vo_velocity_noise_.sigma().value_or(*built_in.vo_increment_noise_m / vo.dt_s);
  }
  if (model_.vo_yaw_increment_noise_rad) {
    n.yaw_rate_sd = *model_.vo_yaw_increment_noise_rad / vo.dt_s;
  } else {
    vo_yaw_rate_noise_.add(0, vo.yaw_rate_rad_s);
    n.yaw_rate_sd =
        vo_yaw_rate_noise_.sigma().value_or(*built_in.vo_yaw_increment_noise_rad / vo.dt_s);
  }
  return n;
}

detail::NedStepModel NedFilterBase::begin_step(const BodyVelocityMeasurement& vo,
                                               const std::optional<HeadingMeasurement>& heading) {
  detail::NedStepModel m;
  const TimeNs t = vo.t_ns;
  if (started_) {
    if (t <= t_prev_ns_) {
      throw UserError(std::string(who_) + "::step: time stamps must increase: got t = " +
                      format_seconds(t) + " s after t = " + format_seconds(t_prev_ns_) + " s");
    }
    m.dt = ns_to_seconds(t - t_prev_ns_);
  }
  started_ = true;
  t_prev_ns_ = t;

  bool vo_ok = vo.valid;
  if (vo_ok && !(std::isfinite(vo.surge_m_s) && std::isfinite(vo.sway_m_s) &&
                 std::isfinite(vo.yaw_rate_rad_s) && std::isfinite(vo.dt_s) && vo.dt_s > 0.0)) {
    ++nonfinite_guards_;
    vo_ok = false;
  }
  double psi_input_var;
  if (vo_ok) {
    // "The heading angle is given ... by tracking rotations between frames": the VO yaw is the
    // input that turns psi; its increment noise scales to this step's length.
    m.yaw_rate = vo.yaw_rate_rad_s;
    last_yaw_rate_ = m.yaw_rate;
    const VoNoise noise = vo_noise(vo);
    m.yaw_rate_sd = noise.yaw_rate_sd;
    const double s = noise.yaw_rate_sd * m.dt;
    psi_input_var = s * s;
    m.vo = true;
    m.u = vo.surge_m_s;
    m.v = vo.sway_m_s;
    m.r_uv = noise.velocity_sd * noise.velocity_sd;
  } else {
    vo_velocity_noise_.gap();
    vo_yaw_rate_noise_.gap();
    m.yaw_rate = last_yaw_rate_;
    const double s = model_.unmeasured_yaw_rate_sd_rad_s * m.dt;
    psi_input_var = s * s;
  }
  const double qp = model_.position_noise_m_sqrt_s * model_.position_noise_m_sqrt_s * m.dt;
  const double qv = model_.velocity_noise_m_s_sqrt_s * model_.velocity_noise_m_s_sqrt_s * m.dt;
  const double qh = model_.heading_noise_rad_sqrt_s * model_.heading_noise_rad_sqrt_s * m.dt;
  m.q << qp, qp, qv, qv, qh + psi_input_var;

  if (heading) {
    if (std::isfinite(heading->heading_rad)) {
      // The sample's age (<= one compass period) is made up with the yaw rate (ours).
      const double age_s = ns_to_seconds(t - heading->t_ns);
      m.heading = true;
      m.psi = wrap_angle_rad(heading->heading_rad + m.yaw_rate * age_s);
      m.r_psi = *model_.compass_noise_rad * *model_.compass_noise_rad;
    } else {
      ++nonfinite_guards_;
    }
  }
  return m;
}

// ---------------------------------------------------------------------------------------------

NedKalmanFilter::NedKalmanFilter(const Options& options, const NedState& initial)
    : NedFilterBase(validated(options, "NedKalmanFilter"), initial, "NedKalmanFilter") {
  reset();
}

void NedKalmanFilter::reset() {
  reset_clock();
  x_ = x0_;
  P_ = prior_variance().asDiagonal();
  last_ = NedEstimate{};
  last_.x = x_;
  last_.P = P_;
}

NedEstimate NedKalmanFilter::step(const BodyVelocityMeasurement& vo,
                                  const std::optional<HeadingMeasurement>& heading) {
  const detail::NedStepModel m = begin_step(vo, heading);
  NedEstimate out;
  out.t_ns = vo.t_ns;
  out.dt_s = m.dt;

  if (m.dt > 0.0) {
    // Eq. (2), with the yaw increment r dt as the known input on psi.
    const double dt = m.dt;
    const double psi_m = x_(ned::kHeading) + 0.5 * m.yaw_rate * dt;
    const double c = std::cos(psi_m), s = std::sin(psi_m);
    NedMatrix Phi = NedMatrix::Identity();
    Phi(ned::kNorth, ned::kSurge) = dt * c;
    Phi(ned::kNorth, ned::kSway) = -dt * s;
    Phi(ned::kEast, ned::kSurge) = dt * s;
    Phi(ned::kEast, ned::kSway) = dt * c;
    if (model_.heading_jacobian) {
      const double u = x_(ned::kSurge), v = x_(ned::kSway);
      Phi(ned::kNorth, ned::kHeading) = -dt * (u * s + v * c);
      Phi(ned::kEast, ned::kHeading) = dt * (u * c - v * s);
    }
    propagate_mean(&x_, dt, m.yaw_rate * dt);
    // Eq. (3).
    P_ = Phi * P_ * Phi.transpose();
    P_.diagonal() += m.q;
  }
  if (m.vo) {
    scalar_update(&x_, &P_, ned::kSurge, m.u - x_(ned::kSurge), m.r_uv);
    scalar_update(&x_, &P_, ned::kSway, m.v - x_(ned::kSway), m.r_uv);
    out.vo_fused = true;
    out.vo_velocity_sd_m_s = std::sqrt(m.r_uv);
    out.vo_yaw_rate_sd_rad_s = m.yaw_rate_sd;
  }
  if (m.heading) {
    scalar_update(&x_, &P_, ned::kHeading, wrap_angle_rad(m.psi - x_(ned::kHeading)), m.r_psi);
    out.heading_fused = true;
  }
  x_(ned::kHeading) = wrap_angle_rad(x_(ned::kHeading));
  if (!finite(x_) || !P_.allFinite()) {
    // Never expected (validated noise, checked inputs); restart rather than spread NaN.
    ++nonfinite_guards_;
    x_ = x0_;
    P_ = prior_variance().asDiagonal();
    out.vo_fused = out.heading_fused = false;
  }
  out.x = x_;
  out.P = P_;
  last_ = out;
  return out;
}

// ---------------------------------------------------------------------------------------------

NedParticleFilter::NedParticleFilter(const Options& options, Rng rng, const NedState& initial)
    : NedFilterBase(validated(options, "NedParticleFilter"), initial, "NedParticleFilter"),
      options_(options),
      rng_initial_(rng),
      rng_(rng) {
  const auto n = static_cast<std::size_t>(options_.particles);
  particles_.resize(n);
  weights_.resize(n);
  scratch_.resize(n);
  log_l_.resize(n);
  cumulative_.resize(n);
  reset();
}

void NedParticleFilter::draw_initial_particles() {
  // "Initialized with N particles with different states sampled from a normal distribution."
  const NedVector sd = prior_variance().cwiseSqrt();
  for (NedVector& p : particles_) {
    for (int j = 0; j < ned::kDim; ++j) p(j) = x0_(j) + sd(j) * rng_.normal();
    p(ned::kHeading) = wrap_angle_rad(p(ned::kHeading));
  }
  std::fill(weights_.begin(), weights_.end(), 1.0 / static_cast<double>(particles_.size()));
}

void NedParticleFilter::reset() {
  reset_clock();
  rng_ = rng_initial_;
  resample_count_ = 0;
  draw_initial_particles();
  last_ = weighted_estimate();
  if (options_.position == PfPosition::kIntegrated) last_.x.head<2>() = x0_.head<2>();
}

NedEstimate NedParticleFilter::weighted_estimate() const {
  // Eq. (10); the weights are normalised, so the denominator is 1. The heading is averaged on
  // the circle (atan2 of the weighted sines and cosines) so that +-pi do not average to 0.
  NedEstimate e;
  double sx = 0.0, sy = 0.0;
  NedVector mean = NedVector::Zero();
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    const double w = weights_[i];
    mean += w * particles_[i];
    sx += w * std::cos(particles_[i](ned::kHeading));
    sy += w * std::sin(particles_[i](ned::kHeading));
  }
  mean(ned::kHeading) = std::atan2(sy, sx);
  NedMatrix P = NedMatrix::Zero();
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    NedVector d = particles_[i] - mean;
    d(ned::kHeading) = wrap_angle_rad(d(ned::kHeading));
    P.noalias() += weights_[i] * d * d.transpose();
  }
  e.x = mean;
  e.P = P;
  return e;
}

void NedParticleFilter::resample() {
  const std::size_t n = particles_.size();
  double c = 0.0;
  for (std::size_t i = 0; i < n; ++i) cumulative_[i] = (c += weights_[i]);
  const double total = cumulative_[n - 1];
  if (options_.resampling == PfResampling::kMultinomial) {
    // The paper's scheme: "the weight of a particle represents the probability of choosing the
    // particle to be in a new set of particles" -- N independent draws.
    for (std::size_t i = 0; i < n; ++i) {
      const double u = rng_.uniform() * total;
      auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), u);
      const auto j =
          std::min<std::size_t>(static_cast<std::size_t>(it - cumulative_.begin()), n - 1);
      scratch_[i] = particles_[j];
    }
  } else {
    // Systematic: one uniform offset, N pointers 1/N apart (Kitagawa 1996); lower variance than
    // multinomial and O(N).
    const double step = total / static_cast<double>(n);
    const double u0 = rng_.uniform() * step;
    std::size_t j = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double target = u0 + static_cast<double>(i) * step;
      while (j + 1 < n && cumulative_[j] <= target) ++j;
      scratch_[i] = particles_[j];
    }
  }
  particles_.swap(scratch_);
  std::fill(weights_.begin(), weights_.end(), 1.0 / static_cast<double>(n));
  ++resample_count_;
}

// Eqs. (8)-(9): each particle's weight times the likelihood of this step's measurements;
// returns the effective sample size after.
double NedParticleFilter::reweight(const detail::NedStepModel& m) {
  const std::size_t n = particles_.size();
  // Eq. (8): likelihood of z_k given each particle, in the log domain (no underflow).
  const double two_pi = 2.0 * std::numbers::pi;
  const int components = (m.vo ? 2 : 0) + (m.heading ? 1 : 0);
  double max_l = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const NedVector& p = particles_[i];
    double res[3], var[3];
    int k = 0;
    if (m.vo) {
      res[k] = m.u - p(ned::kSurge);
      var[k++] = m.r_uv;
      res[k] = m.v - p(ned::kSway);
      var[k++] = m.r_uv;
    }
    if (m.heading) {
      res[k] = wrap_angle_rad(m.psi - p(ned::kHeading));
      var[k++] = m.r_psi;
    }
    double l;
    if (options_.likelihood == PfLikelihood::kGaussian) {
      l = 0.0;
      for (int c = 0; c < components; ++c) l -= 0.5 * res[c] * res[c] / var[c];
    } else {
      // Avg over the components of N(res; 0, var), as a log-sum-exp.
      double a[3];
      double amax = -std::numeric_limits<double>::infinity();
      for (int c = 0; c < components; ++c) {
        a[c] = -0.5 * std::log(two_pi * var[c]) - 0.5 * res[c] * res[c] / var[c];
        amax = std::max(amax, a[c]);
      }
      double s = 0.0;
      for (int c = 0; c < components; ++c) s += std::exp(a[c] - amax);
      l = amax + std::log(s / components);
    }
    log_l_[i] = l;
    max_l = std::max(max_l, l);
  }
  // Eq. (9): normalised weights (times the previous weights, which are uniform after a
  // resampling).
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) total += (weights_[i] *= std::exp(log_l_[i] - max_l));
  if (!(total > 0.0) || !std::isfinite(total)) {
    // Every particle with weight left is far out in the tails: keep the likelihood alone.
    ++nonfinite_guards_;
    total = 0.0;
    for (std::size_t i = 0; i < n; ++i) total += (weights_[i] = std::exp(log_l_[i] - max_l));
  }
  double s2 = 0.0;
  for (double& w : weights_) {
    w /= total;
    s2 += w * w;
  }
  return 1.0 / s2;
}

NedEstimate NedParticleFilter::step(const BodyVelocityMeasurement& vo,
                                    const std::optional<HeadingMeasurement>& heading) {
  const detail::NedStepModel m = begin_step(vo, heading);
  const std::size_t n = particles_.size();

  if (m.dt > 0.0) {
    // Eq. (7): each particle through the motion model plus Gaussian noise omega ~ N(0, Q).
    const NedVector sd = m.q.cwiseSqrt();
    const double dpsi = m.yaw_rate * m.dt;
    for (NedVector& p : particles_) {
      propagate_mean(&p, m.dt, dpsi);
      for (int j = 0; j < ned::kDim; ++j) p(j) += sd(j) * rng_.normal();
      p(ned::kHeading) = wrap_angle_rad(p(ned::kHeading));
    }
  }

  double w2 = 0.0;
  for (double w : weights_) w2 += w * w;
  double ess = 1.0 / w2;
  bool resampled = false;
  if (m.vo || m.heading) ess = reweight(m);

  NedEstimate out = weighted_estimate();
  if (options_.position == PfPosition::kIntegrated) {
    // Eq. (7)'s mean on the previous estimate, with this step's velocity: the Kalman filter's
    // predicted position plus the correction its gain makes through the position-velocity
    // covariance (dt times the velocity's).
    NedVector moved = last_.x;
    moved(ned::kSurge) = out.x(ned::kSurge);
    moved(ned::kSway) = out.x(ned::kSway);
    if (m.dt > 0.0) propagate_mean(&moved, m.dt, m.yaw_rate * m.dt);
    out.x(ned::kNorth) = moved(ned::kNorth);
    out.x(ned::kEast) = moved(ned::kEast);
  }
  out.t_ns = vo.t_ns;
  out.dt_s = m.dt;
  out.vo_fused = m.vo;
  out.heading_fused = m.heading;
  out.effective_sample_size = ess;
  if (m.vo) {
    out.vo_velocity_sd_m_s = std::sqrt(m.r_uv);
    out.vo_yaw_rate_sd_rad_s = m.yaw_rate_sd;
  }
  if (m.vo || m.heading) {
    resampled = options_.resampling == PfResampling::kMultinomial ||
                ess < options_.ess_threshold * static_cast<double>(n);
    if (resampled) resample();
  }
  out.resampled = resampled;
  if (!out.x.allFinite() || !out.P.allFinite()) {
    ++nonfinite_guards_;
    rng_ = rng_initial_;
    draw_initial_particles();
    const NedEstimate prior = weighted_estimate();
    out.x = prior.x;
    out.P = prior.P;
    out.vo_fused = out.heading_fused = false;
  }
  last_ = out;
  return out;
}

// ---------------------------------------------------------------------------------------------

NedCsvWriter::NedCsvWriter(const std::filesystem::path& path) : file_(path) {
  file_.write("t_s,north_m,east_m,surge_m_s,sway_m_s,heading_rad\n");
}

void NedCsvWriter::write(const NedEstimate& e) {
  DRIFTLAB_DEMAND_MSG(e.x.allFinite(),
                      fmt::format("NED estimate at t = {} ns is not finite", e.t_ns));
  DRIFTLAB_DEMAND_MSG(!any_ || e.t_ns > last_ns_,
                      fmt::format("NED estimate time stamps do not increase at t = {} ns", e.t_ns));
  any_ = true;
  last_ns_ = e.t_ns;
  line_ = format_seconds(e.t_ns);
  for (int j = 0; j < ned::kDim; ++j) append_double(&line_, e.x(j));
  line_ += '\n';
  file_.write(line_);
}

void write_ned_csv(const std::filesystem::path& path, std::span<const NedEstimate> steps) {
  NedCsvWriter w(path);
  for (const NedEstimate& e : steps) w.write(e);
  w.commit();
}

}  // namespace driftlab::fusion
