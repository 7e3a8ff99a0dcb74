#include "eval/evaluate.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "core/record_json.hpp"
#include "core/rotation.hpp"
#include "core/yaml_io.hpp"

namespace driftlab::eval {
namespace {

std::vector<Vec3> positions(const std::vector<SE3>& poses) {
  std::vector<Vec3> p;
  p.reserve(poses.size());
  for (const auto& T : poses) p.push_back(T.translation());
  return p;
}

void regress(const EvalOptions& options, Evaluation* e) {
  const auto& names = options.regression_covariates;
  std::vector<std::string> missing;
  for (const auto& name : names) {
    bool any = false;
    for (const auto& s : e->sections) any = any || std::isfinite(s.covariate(name));
    if (!any) missing.push_back(name);
  }
  if (!missing.empty()) {
    std::string available;
    if (!e->sections.empty())
      for (const auto& n : e->sections.front().covariate_names)
        available += (available.empty() ? "" : ", ") + n;
    std::string list;
    for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
    e->regression_skipped =
        fmt::format("covariate(s) {} not available{}", list,
                    available.empty()
                        ? " (no sections)"
                        : "; available: " + available + " (f and d need per-frame VO statistics)");
    return;
  }
  std::vector<double> y;
  std::vector<std::vector<double>> columns(names.size());
  std::size_t dropped = 0;
  for (const auto& s : e->sections) {
    bool complete = true;
    for (const auto& name : names) complete = complete && std::isfinite(s.covariate(name));
    if (!complete) {
      ++dropped;
      continue;
    }
    y.push_back(s.per_m(s.err_p_m));
    for (std::size_t k = 0; k < names.size(); ++k) columns[k].push_back(s.covariate(names[k]));
  }
  if (dropped)
    e->warnings.push_back(
        fmt::format("regression: {} of {} sections lack a covariate value and were left out",
                    dropped, e->sections.size()));
  if (y.size() < names.size() + 2) {
    e->regression_skipped =
        fmt::format("got {} sections, need at least {} for {} covariates and an intercept",
                    y.size(), names.size() + 2, names.size());
    return;
  }
  try {
    e->regression = ols(y, columns, names, OlsOptions{});
  } catch (const UserError& err) {
    e->regression_skipped = err.what();
  }
}

}  // namespace

namespace {

// A section whose frames include one where the VO lost track (frame table column `lost`,
// 1 for such a frame) is marked, and Table 1 is also summarised without the marked ones, so
// that a stretch of lost frames is not averaged into the errors unseen.
void mark_lost_track_sections(const FrameTable* frames, Evaluation* e) {
  if (!frames || !frames->column("lost") || e->sections.empty()) return;
  std::vector<Section> tracked;
  for (const Section& s : e->sections) {
    if (s.covariate("lost") > 0)
      e->lost_track_sections.push_back(s.index);
    else
      tracked.push_back(s);
  }
  e->tracked_summary = summarize_sections(tracked);
  if (e->lost_track_sections.empty()) return;
  e->warnings.push_back(fmt::format(
      "{} of {} sections hold frames where the VO lost track: mean e'_p {:.4g} m/m over all "
      "sections, {:.4g} m/m over the {} others (sections.tracked in metrics.json)",
      e->lost_track_sections.size(), e->sections.size(), e->section_summary.p_m_per_m.mean,
      e->tracked_summary->p_m_per_m.mean, tracked.size()));
}

// The pose of the reference point l_C (eval.reference_point_m): the camera's orientation at
// p_W + R_W_C l_C.
SE3 at_reference_point(const SE3& T_W_C, const std::array<double, 3>& l_C) {
  if (l_C == std::array<double, 3>{0.0, 0.0, 0.0}) return T_W_C;
  return SE3(T_W_C.quaternion(),
             T_W_C.translation() + T_W_C.quaternion() * Vec3(l_C[0], l_C[1], l_C[2]));
}

}  // namespace

Evaluation evaluate(const EvaluationInput& in) {
  yaml::validate_or_throw(in.options, "eval options");
  const EvalOptions& opt = in.options;
  Evaluation e;
  e.algorithm = in.algorithm;
  e.gt_poses = in.gt.size();
  e.est_poses = in.est.size();
  e.association = associate(in.gt, in.est, seconds_to_ns(opt.association_tolerance_s), in.gt_label,
                            in.est_label);
  std::vector<TimeNs> t;
  std::vector<SE3> gt, est;
  for (std::size_t k = 0; k < e.association.size(); ++k) {
    t.push_back(in.est[e.association.est[k]].t_ns);
    gt.push_back(at_reference_point(in.gt[e.association.gt[k]].T_W_C, opt.reference_point_m));
    est.push_back(in.est[e.association.est[k]].T_W_C);
  }
  const std::size_t unpaired = in.est.size() - e.association.size();
  if (unpaired)
    e.warnings.push_back(fmt::format("{} of {} estimate poses have no ground truth within {} s",
                                     unpaired, in.est.size(), opt.association_tolerance_s));

  // Absolute errors: after alignment (river paper: Horn's method [48]), never a rotation the
  // geometry leaves unobservable.
  AlignmentFit fit = fit_alignment(opt.align, positions(est), positions(gt), opt.align_first_n);
  e.alignment = fit.transform;
  if (!fit.warning.empty()) e.warnings.push_back(std::move(fit.warning));
  const std::vector<SE3> est_aligned = e.alignment.apply(est);
  e.ape = ape(gt, est_aligned);
  e.track = track_errors(gt, est_aligned, opt.length_sample_m);
  for (const auto& sub : opt.subtracks) {
    std::vector<SE3> g, s;
    for (std::size_t k = 0; k < t.size(); ++k) {
      const double ts = ns_to_seconds(t[k] - t.front());
      if (ts >= sub.start_s && ts <= sub.end_s) {
        g.push_back(gt[k]);
        s.push_back(est[k]);
      }
    }
    if (g.size() < 3) {
      e.warnings.push_back(fmt::format("subtrack '{}': {} poses in [{}, {}] s, need at least 3",
                                       sub.name, g.size(), sub.start_s, sub.end_s));
      continue;
    }
    AlignmentFit sub_fit = fit_alignment(opt.align, positions(s), positions(g), 0);
    if (!sub_fit.warning.empty())
      e.warnings.push_back(fmt::format("subtrack '{}': {}", sub.name, sub_fit.warning));
    e.subtracks.push_back(
        {sub.name, track_errors(g, sub_fit.transform.apply(s), opt.length_sample_m)});
  }

  // Relative errors need no alignment.
  RpeOptions rpe_options;
  rpe_options.delta = opt.rpe_delta;
  rpe_options.unit = opt.rpe_unit == RpeUnit::kFrames ? DeltaUnit::kFrames : DeltaUnit::kMeters;
  try {
    e.rpe = rpe(gt, est, rpe_options);
  } catch (const UserError& err) {
    e.warnings.push_back(std::string("rpe: ") + err.what());
  }
  e.kitti = kitti_segment_errors(gt, est, opt.kitti_lengths_m);

  // River paper Section 2.4.
  const FrameTable* frames = in.frames ? &*in.frames : nullptr;
  e.sections = compute_sections(t, gt, est, {opt.section_length_m}, frames);
  e.section_summary = summarize_sections(e.sections);
  mark_lost_track_sections(frames, &e);
  if (!e.sections.empty())
    for (const auto& name : e.sections.front().covariate_names)
      e.covariates.emplace_back(name, summarize_covariate(e.sections, name));
  if (e.sections.empty())
    e.warnings.push_back(
        fmt::format("the ground-truth track ({:.3f} m) is shorter than one "
                    "section of {} m: no section errors",
                    path_length_m(gt), opt.section_length_m));
  regress(opt, &e);
  if (in.attitude_reference) {
    e.paper_attitude = paper_attitude(t, est, e.sections, *in.attitude_reference,
                                      seconds_to_ns(opt.association_tolerance_s));
    if (e.paper_attitude->pairs == 0)
      e.warnings.push_back(fmt::format("no estimate pose within {} s of the attitude reference",
                                       opt.association_tolerance_s));
  }

  // Basin paper table: planar states of the camera, truth vs aligned estimate; the heading of
  // the estimate as it came, since a fit of positions says nothing about it.
  PlanarStates est_states = planar_states(t, est_aligned, true);
  est_states.heading_rad = planar_states(t, est, true).heading_rad;
  e.basin = basin_table(planar_states(t, gt, true), est_states);
  if (in.basin_reference) {
    e.basin_reference_name = in.basin_reference_name;
    e.basin_reference =
        basin_table(*in.basin_reference, t, est_states, seconds_to_ns(opt.association_tolerance_s),
                    &e.basin_reference_pairs);
    if (e.basin_reference_pairs == 0)
      e.warnings.push_back(fmt::format("no estimate pose within {} s of the {}'s times",
                                       opt.association_tolerance_s, e.basin_reference_name));
  }
  return e;
}

std::string Evaluation::brief() const {
  std::string s =
      fmt::format("{}: {} pairs, APE RMSE {:.4f} m, track RMSE 3D {:.4f} m ({:.2f} %)", algorithm,
                  association.size(), ape.trans_m.rmse, track.rmse_3d_m, track.rmse_3d_pct);
  s += fmt::format(", {} sections (mean e'_p {:.4f} m/m)", sections.size(),
                   section_summary.p_m_per_m.mean);
  if (regression)
    s += fmt::format(", regression R^2 {:.3f}", regression->r2);
  else if (!regression_skipped.empty())
    s += ", no regression (" + regression_skipped + ")";
  return s;
}

// ---------------------------------------------------------------------------
// metrics.json

namespace {

CommonStats common_stats(const Summary& s) { return {s.n, s.min, s.max, s.mean, s.median, s.rmse}; }

ErrorStats error_stats(const Summary& s) { return {common_stats(s), s.std_population}; }

SampleStats sample_stats(const Summary& s) { return {common_stats(s), s.sd_sample}; }

TrackRecord track_record(const TrackErrors& t) {
  return {t.n,          t.rmse_3d_m,   t.max_3d_m,     t.rmse_2d_m,
          t.max_2d_m,   t.rmse_3d_pct, t.max_3d_pct,   t.rmse_2d_pct,
          t.max_2d_pct, t.length_gt_m, t.length_est_m, t.length_error_pct};
}

Table1Rows table1_rows(const SectionSummary& ss) {
  return {sample_stats(ss.p_m_per_m),      sample_stats(ss.x_m_per_m),
          sample_stats(ss.y_m_per_m),      sample_stats(ss.z_m_per_m),
          sample_stats(ss.roll_deg_per_m), sample_stats(ss.pitch_deg_per_m),
          sample_stats(ss.yaw_deg_per_m)};
}

BasinRows basin_rows(const BasinTable& t) {
  const auto row = [](const Summary& s) { return BasinRow{s.rmse, s.sd_sample, s.n}; };
  return {row(t.north_m), row(t.east_m), row(t.surge_m_s), row(t.sway_m_s), row(t.heading_deg)};
}

RegressionRecord regression_record(const Evaluation& e) {
  RegressionRecord r;
  if (!e.regression) {
    r.skipped = e.regression_skipped;
    return r;
  }
  const OlsResult& ols = *e.regression;
  r.n = ols.n;
  r.r2 = ols.r2;
  r.adj_r2 = ols.adj_r2;
  r.f = ols.f;
  r.f_p = ols.f_p;
  r.sigma = ols.sigma;
  r.coefficients.emplace();
  for (const auto& c : ols.coefficients)
    (*r.coefficients)[c.name] = {c.estimate, c.std_error, c.t, c.p, c.vif, c.significant};
  const OlsDiagnostics& d = ols.diagnostics;
  r.diagnostics =
      DiagnosticsRecord{d.jarque_bera,      d.jarque_bera_p,   d.shapiro_wilk_w, d.shapiro_wilk_p,
                        d.breusch_pagan_lm, d.breusch_pagan_p, d.durbin_watson,  d.max_vif};
  r.warnings = ols.warnings;
  return r;
}

void add_sections(const Evaluation& e, const EvalOptions& options, EvaluationRecord* r) {
  r->sections.section_length_m = options.section_length_m;
  r->sections.count = e.sections.size();
  r->sections.rows = table1_rows(e.section_summary);
  if (e.tracked_summary) {
    r->sections.with_lost_track = e.lost_track_sections;
    r->sections.tracked = TrackedSections{e.sections.size() - e.lost_track_sections.size(),
                                          table1_rows(*e.tracked_summary)};
  }
  if (e.paper_attitude) {
    const PaperAttitude& a = *e.paper_attitude;
    r->paper_attitude =
        PaperAttitudeRecord{"ahrs",
                            a.pairs,
                            sample_stats(a.roll_deg_per_m),
                            sample_stats(a.pitch_deg_per_m),
                            sample_stats(a.yaw_deg_per_m),
                            {rad2deg(a.max_abs_rad.roll_rad), rad2deg(a.max_abs_rad.pitch_rad),
                             rad2deg(a.max_abs_rad.yaw_rad)}};
  }
  for (const auto& [name, summary] : e.covariates) r->covariates[name] = sample_stats(summary);
  r->regression = regression_record(e);
}

}  // namespace

EvaluationRecord evaluation_record(const Evaluation& e, const EvalOptions& options) {
  EvaluationRecord r;
  r.algorithm = e.algorithm;
  r.association = {e.association.size(), e.gt_poses, e.est_poses, options.association_tolerance_s,
                   options.reference_point_m};
  r.alignment.method = std::string(yaml::enum_name(options.align));
  r.alignment.first_n = options.align_first_n;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) r.alignment.rotation[i][k] = e.alignment.R(i, k);
  r.alignment.translation_m = {e.alignment.t.x(), e.alignment.t.y(), e.alignment.t.z()};
  r.alignment.scale = e.alignment.scale;
  r.ape = {error_stats(e.ape.trans_m), error_stats(e.ape.rot_deg)};
  r.rpe = {options.rpe_delta,
           std::string(yaml::enum_name(options.rpe_unit)),
           e.rpe.pairs,
           {error_stats(e.rpe.trans_m), error_stats(e.rpe.rot_deg)}};
  r.track = track_record(e.track);
  for (const auto& s : e.subtracks) r.subtracks[s.name] = track_record(s.track);
  add_sections(e, options, &r);
  r.basin = basin_rows(e.basin);
  if (e.basin_reference)
    r.basin_overhead = BasinReferenceRecord{basin_rows(*e.basin_reference), e.basin_reference_name,
                                            e.basin_reference_pairs};
  for (const auto& k : e.kitti)
    r.kitti.push_back({k.length_m, k.count, k.trans_err_pct, k.rot_err_deg_per_100m});
  r.warnings = e.warnings;
  // A number that is not finite is written as null; the warnings name each one.
  std::vector<record_json::NonFinite> nonfinite;
  record_json::to_json(r, &nonfinite);
  for (const auto& [key, value] : nonfinite)
    r.warnings.push_back(
        fmt::format("{} is not finite ({}); written as null", key, yaml::format_double(value)));
  return r;
}

nlohmann::json to_json(const Evaluation& e, const EvalOptions& options) {
  return record_json::to_json(evaluation_record(e, options));
}

// ---------------------------------------------------------------------------
// sections.csv

std::string sections_csv(const Evaluation& e) {
  std::string out =
      "algorithm,index,t_start_s,t_end_s,length_m,err_x_m,err_y_m,err_z_m,err_p_m,"
      "err_roll_deg,err_pitch_deg,err_yaw_deg,x_m_per_m,y_m_per_m,z_m_per_m,p_m_per_m,"
      "roll_deg_per_m,pitch_deg_per_m,yaw_deg_per_m";
  if (!e.sections.empty())
    for (const auto& n : e.sections.front().covariate_names) out += "," + n;
  out += "\n";
  auto num = [](double v) { return std::isfinite(v) ? yaml::format_double(v) : std::string(); };
  for (const auto& s : e.sections) {
    const double roll = rad2deg(s.err_rad.roll_rad), pitch = rad2deg(s.err_rad.pitch_rad),
                 yaw = rad2deg(s.err_rad.yaw_rad);
    out += fmt::format(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", e.algorithm, s.index,
        format_seconds(s.t_start_ns), format_seconds(s.t_end_ns), num(s.length_m), num(s.err_m.x()),
        num(s.err_m.y()), num(s.err_m.z()), num(s.err_p_m), num(roll), num(pitch), num(yaw),
        num(s.per_m(s.err_m.x())), num(s.per_m(s.err_m.y())), num(s.per_m(s.err_m.z())),
        num(s.per_m(s.err_p_m)), num(s.per_m(roll)), num(s.per_m(pitch)), num(s.per_m(yaw)));
    for (double c : s.covariates) out += "," + num(c);
    out += "\n";
  }
  return out;
}

// ---------------------------------------------------------------------------
// tables.md

namespace {

std::string fixed(double v, int digits) {
  return std::isfinite(v) ? fmt::format("{:.{}f}", v, digits) : std::string("—");
}

std::string summary_row(const std::string& label, const Summary& s, int digits, bool with_n) {
  return fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", label, fixed(s.min, digits),
                     fixed(s.mean, digits), fixed(s.median, digits), fixed(s.sd_sample, digits),
                     fixed(s.max, digits), with_n ? std::to_string(s.n) : "");
}

}  // namespace

std::string tables_markdown(const Evaluation& e, const EvalOptions& options) {
  std::string md = fmt::format("# Evaluation of {}\n\n{}\n\n", e.algorithm, e.brief());
  const SectionSummary& ss = e.section_summary;
  md += fmt::format(
      "## Table 1. Position and translation error over displacement (m/m) and angular errors "
      "over displacement (deg/m), from n sections of {} m (river paper Table 1)\n\n",
      yaml::format_double(options.section_length_m));
  md += "| error | Min | Mean | Median | SD | Max | n |\n|---|---|---|---|---|---|---|\n";
  md += summary_row("ε'_p", ss.p_m_per_m, 3, true);
  md += summary_row("ε'_x (optical axis)", ss.x_m_per_m, 3, false);
  md += summary_row("ε'_y (right)", ss.y_m_per_m, 3, false);
  md += summary_row("ε'_z (down)", ss.z_m_per_m, 3, false);
  md += summary_row("ε'_roll", ss.roll_deg_per_m, 2, false);
  md += summary_row("ε'_pitch", ss.pitch_deg_per_m, 2, false);
  md += summary_row("ε'_yaw", ss.yaw_deg_per_m, 2, false);
  if (e.paper_attitude) {
    const PaperAttitude& a = *e.paper_attitude;
    md +=
        summary_row("ε'_roll, AHRS − VO angles (the paper's Eq. (11))", a.roll_deg_per_m, 2, true);
    md += summary_row("ε'_pitch, AHRS − VO angles", a.pitch_deg_per_m, 2, false);
    md += summary_row("ε'_yaw, AHRS − VO angles", a.yaw_deg_per_m, 2, false);
    md += fmt::format(
        "\nThe last three rows compare, as the river paper did, the AHRS's Euler angles in its "
        "own frame with the VO's in its first camera's frame; along the whole track their "
        "difference strays at most {} (roll), {} (pitch) and {} (yaw) deg from its start "
        "(the paper's Section 3.1 maxima).\n",
        fixed(rad2deg(a.max_abs_rad.roll_rad), 2), fixed(rad2deg(a.max_abs_rad.pitch_rad), 2),
        fixed(rad2deg(a.max_abs_rad.yaw_rad), 2));
  }
  if (e.tracked_summary && !e.lost_track_sections.empty()) {
    const std::size_t n = e.lost_track_sections.size();
    md += summary_row(fmt::format("ε'_p, without the {} sections where the VO lost track", n),
                      e.tracked_summary->p_m_per_m, 3, true);
    std::string which;
    for (std::size_t i = 0; i < n && i < 20; ++i)
      which += (i ? ", " : "") + std::to_string(e.lost_track_sections[i]);
    if (n > 20) which += fmt::format(" and {} more", n - 20);
    md += fmt::format(
        "\nThe VO lost track in {} of the {} sections (index {}; their `lost` column in "
        "sections.csv is the share of such frames): the rows above average through them, the "
        "last row leaves them out.\n",
        n, e.sections.size(), which);
  }

  md +=
      "\n## Table 2. RMSE and maximum of the 3D and 2D position errors, m (% of track "
      "length) (river paper Table 2)\n\n";
  md +=
      "| track | 3D RMSE | 3D max | 2D RMSE | 2D max | N | length error |\n"
      "|---|---|---|---|---|---|---|\n";
  auto track_row = [&](const std::string& name, const TrackErrors& t) {
    return fmt::format("| {} | {} ({}) | {} ({}) | {} ({}) | {} ({}) | {} | {} % |\n", name,
                       fixed(t.rmse_3d_m, 2), fixed(t.rmse_3d_pct, 2), fixed(t.max_3d_m, 2),
                       fixed(t.max_3d_pct, 2), fixed(t.rmse_2d_m, 2), fixed(t.rmse_2d_pct, 2),
                       fixed(t.max_2d_m, 2), fixed(t.max_2d_pct, 2), t.n,
                       fixed(t.length_error_pct, 1));
  };
  md += track_row("total trajectory", e.track);
  for (const auto& s : e.subtracks) md += track_row(s.name, s.track);

  md +=
      "\n## Table 3. Multiple linear regression of ε'_p on the covariates (river paper "
      "Table 3); * marks significance at α = 0.05\n\n";
  if (e.regression) {
    const OlsResult& r = *e.regression;
    md += "| term | β | SE | t | p-value (t) | VIF |\n|---|---|---|---|---|---|\n";
    for (const auto& c : r.coefficients)
      md += fmt::format("| {} | {:.2e} | {:.2e} | {:.2f} | {:.2f}{} | {} |\n", c.name, c.estimate,
                        c.std_error, c.t, c.p, c.significant ? " *" : "",
                        c.name == "Intercept" || c.name == "intercept" ? "" : fixed(c.vif, 2));
    md += fmt::format(
        "\nF = {:.2f}, p-value (F) = {:.3g}, R² = {:.2f}, adjusted R² = {:.2f}, n = {}\n", r.f,
        r.f_p, r.r2, r.adj_r2, r.n);
    const OlsDiagnostics& d = r.diagnostics;
    md += fmt::format(
        "\nResidual checks: Jarque-Bera {:.2f} (p {:.3f}); Shapiro-Wilk W {:.3f} (p {:.3f}); "
        "Breusch-Pagan {:.2f} (p {:.3f}); Durbin-Watson {:.2f}; max VIF {:.2f}\n",
        d.jarque_bera, d.jarque_bera_p, d.shapiro_wilk_w, d.shapiro_wilk_p, d.breusch_pagan_lm,
        d.breusch_pagan_p, d.durbin_watson, d.max_vif);
  } else {
    md += "Not computed: " + e.regression_skipped + "\n";
  }

  md +=
      "\n## Table 4. Distribution of the regression covariates over the sections (river "
      "paper Table 4)\n\n";
  md += "| covariate | Min | Mean | Median | SD | Max | n |\n|---|---|---|---|---|---|---|\n";
  for (const auto& [name, s] : e.covariates) md += summary_row(name, s, 2, true);

  md +=
      "\n## Basin paper table: RMSE and standard deviation of the errors (Kučić and Valčić "
      "2020, Tables 2-3)\n\n";
  const auto rows = [&](const BasinTable& b, const std::string& label) {
    std::string r;
    r += fmt::format("| N (cm) | {} | {} | {} |\n", label, fixed(b.north_m.rmse * 100, 3),
                     fixed(b.north_m.sd_sample * 100, 3));
    r += fmt::format("| E (cm) | {} | {} | {} |\n", label, fixed(b.east_m.rmse * 100, 3),
                     fixed(b.east_m.sd_sample * 100, 3));
    r += fmt::format("| u (cm/s) | {} | {} | {} |\n", label, fixed(b.surge_m_s.rmse * 100, 3),
                     fixed(b.surge_m_s.sd_sample * 100, 3));
    r += fmt::format("| v (cm/s) | {} | {} | {} |\n", label, fixed(b.sway_m_s.rmse * 100, 3),
                     fixed(b.sway_m_s.sd_sample * 100, 3));
    r += fmt::format("| ψ (deg) | {} | {} | {} |\n", label, fixed(b.heading_deg.rmse, 3),
                     fixed(b.heading_deg.sd_sample, 3));
    return r;
  };
  md += "| quantity | against | RMSE | std |\n|---|---|---|---|\n";
  md += rows(e.basin, "exact truth");
  if (e.basin_reference) md += rows(*e.basin_reference, e.basin_reference_name);

  md +=
      "\n## Standard metrics\n\n| metric | RMSE | mean | median | std | max |\n"
      "|---|---|---|---|---|---|\n";
  auto std_row = [&](const std::string& name, const Summary& s) {
    return fmt::format("| {} | {} | {} | {} | {} | {} |\n", name, fixed(s.rmse, 4),
                       fixed(s.mean, 4), fixed(s.median, 4), fixed(s.std_population, 4),
                       fixed(s.max, 4));
  };
  md += std_row("APE translation (m)", e.ape.trans_m);
  md += std_row("APE rotation (deg)", e.ape.rot_deg);
  md += std_row("RPE translation (m)", e.rpe.trans_m);
  md += std_row("RPE rotation (deg)", e.rpe.rot_deg);
  if (!e.kitti.empty()) {
    md +=
        "\n| KITTI segment (m) | count | translation error (%) | rotation error (deg/100 m) |\n"
        "|---|---|---|---|\n";
    for (const auto& k : e.kitti)
      md += fmt::format("| {} | {} | {} | {} |\n", yaml::format_double(k.length_m), k.count,
                        fixed(k.trans_err_pct, 3), fixed(k.rot_err_deg_per_100m, 3));
  }
  if (!e.warnings.empty()) {
    md += "\n## Warnings\n\n";
    for (const auto& w : e.warnings) md += "- " + w + "\n";
  }
  return md;
}

}  // namespace driftlab::eval
