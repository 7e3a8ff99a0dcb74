#include "eval/sections.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/yaml_io.hpp"

namespace driftlab::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Yaw angles unwrapped into a continuous sequence, so that a turn through
// +-180 deg does not inflate the standard deviation.
std::vector<double> unwrap(const std::vector<double>& a) {
  std::vector<double> out = a;
  for (std::size_t i = 1; i < out.size(); ++i)
    out[i] = out[i - 1] + wrap_angle_rad(a[i] - a[i - 1]);
  return out;
}

double finite_mean(const std::vector<double>& v) {
  double s = 0;
  std::size_t n = 0;
  for (double x : v)
    if (std::isfinite(x)) {
      s += x;
      ++n;
    }
  return n ? s / static_cast<double>(n) : kNaN;
}

}  // namespace

Mat3 R_optical_frd() { return R_frd_optical().transpose(); }

const std::vector<double>* FrameTable::column(std::string_view name) const {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return &columns[k];
  return nullptr;
}

std::vector<std::string> run_vo_names(const FrameTable& table) {
  std::vector<std::string> vos;
  if (table.column("inliers") || table.column("valid_depth_px") || table.column("mean_depth_m"))
    return vos;
  constexpr std::string_view kValid = "_valid";
  for (const std::string& name : table.names)
    if (name.size() > kValid.size() &&
        name.compare(name.size() - kValid.size(), kValid.size(), kValid) == 0)
      vos.push_back(name.substr(0, name.size() - kValid.size()));
  return vos;
}

std::string run_vo_of(const std::vector<std::string>& vos, const std::string& algorithm) {
  std::string best;
  for (const std::string& vo : vos) {
    if (vo == algorithm) return vo;
    if (algorithm.size() > vo.size() + 1 && algorithm.compare(0, vo.size(), vo) == 0 &&
        algorithm[vo.size()] == '_' && vo.size() > best.size())
      best = vo;
  }
  return best;
}

FrameTable run_vo_covariates(const FrameTable& run, const std::string& vo,
                             const std::string& path) {
  const std::vector<double>* valid = run.column(vo + "_valid");
  if (!valid) {
    std::string present;
    for (const std::string& v : run_vo_names(run)) present += (present.empty() ? "" : ", ") + v;
    throw UserError(
        fmt::format("{}: no columns of a VO called '{}' (expected {}_valid, ...); the "
                    "VOs in this table: {}",
                    path, vo, vo, present.empty() ? "none" : present));
  }
  FrameTable out;
  out.t_ns = run.t_ns;
  auto put = [&](const std::string& name, std::vector<double> column) {
    out.names.push_back(name);
    out.columns.push_back(std::move(column));
  };
  for (const char* attitude : {"yaw_deg", "pitch_deg", "roll_deg"})
    if (const auto* col = run.column(attitude)) put(attitude, *col);
  const auto* features = run.column(vo + "_features");
  const auto* inliers = run.column(vo + "_inliers");
  const auto* depth_px = run.column(vo + "_valid_depth_px");
  std::vector<double> f(run.t_ns.size(), kNaN);
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (!((*valid)[i] > 0)) continue;
    if (features)
      f[i] = (*features)[i];
    else if (depth_px && (*depth_px)[i] > 0)
      f[i] = (*depth_px)[i];
    else if (inliers)
      f[i] = (*inliers)[i];
  }
  if (features || inliers || depth_px) put("inliers", std::move(f));
  if (const auto* d = run.column(vo + "_mean_depth_m")) {
    std::vector<double> depth = *d;
    for (std::size_t i = 0; i < depth.size(); ++i)
      if (!((*valid)[i] > 0)) depth[i] = kNaN;
    put("mean_depth_m", std::move(depth));
  }
  if (const auto* lost = run.column(vo + "_lost")) put("lost", *lost);
  if (const auto* moving = run.column("moving_px")) put("moving_px", *moving);
  return out;
}

double Section::covariate(std::string_view name) const {
  for (std::size_t k = 0; k < covariate_names.size(); ++k)
    if (covariate_names[k] == name) return covariates[k];
  return kNaN;
}

FrameTable read_frame_table(const std::string& path) {
  const CsvTable csv = read_csv_table(read_text_file(path, "frame table"), path,
                                      {.trim = CsvTrim::kSpaces, .comments = true});
  const std::vector<std::string>& header = csv.header;
  if (csv.header_line == 0)
    throw UserError(fmt::format("{}: no header line, expected CSV with a header", path));
  const std::size_t line_no = csv.header_line;
  int time_col = -1;
  bool time_in_ns = false;
  FrameTable table;
  std::vector<int> col_of_cell(header.size(), -1);
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (header[c] == "t_ns" || header[c] == "t" || header[c] == "t_s") {
      if (time_col >= 0)
        throw UserError(fmt::format("{}:{}: two time columns ('{}' and '{}'), expected one", path,
                                    line_no, header[static_cast<std::size_t>(time_col)],
                                    header[c]));
      time_col = static_cast<int>(c);
      time_in_ns = header[c] == "t_ns";
    } else {
      if (header[c].empty())
        throw UserError(fmt::format("{}:{}: column {} has an empty name", path, line_no, c + 1));
      col_of_cell[c] = static_cast<int>(table.names.size());
      table.names.push_back(header[c]);
    }
  }
  if (time_col < 0)
    throw UserError(
        fmt::format("{}:{}: no time column, expected one named t_ns, t or t_s", path, line_no));
  table.columns.resize(table.names.size());
  for (const CsvTable::Row& row : csv.rows) {
    const std::vector<std::string>& cells = row.cells;
    const std::string& tcell = cells[static_cast<std::size_t>(time_col)];
    TimeNs t = 0;
    std::int64_t ti = 0;
    if (time_in_ns ? !yaml::parse_int64(tcell, &ti) : !parse_seconds(tcell, &t))
      throw UserError(fmt::format("{}:{}: {}: got '{}', expected a time in {}", path, row.line,
                                  header[static_cast<std::size_t>(time_col)], tcell,
                                  time_in_ns ? "integer nanoseconds" : "seconds"));
    if (time_in_ns) t = ti;
    if (!table.t_ns.empty() && t <= table.t_ns.back())
      throw UserError(
          fmt::format("{}:{}: time {} is not after the previous row's {}, expected "
                      "strictly increasing times",
                      path, row.line, format_seconds(t), format_seconds(table.t_ns.back())));
    table.t_ns.push_back(t);
    for (std::size_t c = 0; c < cells.size(); ++c) {
      if (col_of_cell[c] < 0) continue;
      double v = kNaN;
      if (!cells[c].empty() && cells[c] != "nan" && !yaml::parse_double(cells[c], &v))
        throw UserError(fmt::format("{}:{}: {}: got '{}', expected a number", path, row.line,
                                    header[c], cells[c]));
      if (!std::isfinite(v)) v = kNaN;
      table.columns[static_cast<std::size_t>(col_of_cell[c])].push_back(v);
    }
  }
  return table;
}

std::vector<Section> compute_sections(const std::vector<TimeNs>& t_ns,
                                      const std::vector<SE3>& T_W_C_gt,
                                      const std::vector<SE3>& T_W_C_est,
                                      const SectionOptions& options, const FrameTable* frames) {
  DRIFTLAB_DEMAND(t_ns.size() == T_W_C_gt.size() && t_ns.size() == T_W_C_est.size());
  if (!(options.section_length_m > 0))
    throw UserError(
        fmt::format("section_length_m: got {}, expected a value > 0", options.section_length_m));
  const std::size_t n = t_ns.size();
  const SE3 T_C_F(R_optical_frd(), Vec3::Zero());  // camera FRD axes -> optical
  std::vector<SE3> G(n), E(n);
  for (std::size_t i = 0; i < n; ++i) {
    G[i] = T_W_C_gt[i] * T_C_F;
    E[i] = T_W_C_est[i] * T_C_F;
  }
  // Cumulative ground-truth path length.
  std::vector<double> s(n, 0.0);
  for (std::size_t i = 1; i < n; ++i)
    s[i] = s[i - 1] + (G[i].translation() - G[i - 1].translation()).norm();

  // Platform attitude for h and the pitch/roll covariates, in degrees.
  auto frame_column = [&](const char* name) -> const std::vector<double>* {
    return frames ? frames->column(name) : nullptr;
  };

  std::vector<Section> sections;
  std::size_t start = 0;
  while (start < n) {
    std::size_t end = start;
    while (end < n && s[end] - s[start] < options.section_length_m) ++end;
    if (end >= n) break;  // the remainder is shorter than a section
    Section sec;
    sec.index = sections.size();
    sec.first = start;
    sec.last = end;
    sec.t_start_ns = t_ns[start];
    sec.t_end_ns = t_ns[end];
    sec.length_m = s[end] - s[start];
    // Re-anchoring the estimate at the section start = comparing the relative
    // motions over the section, both expressed in the start camera's axes.
    const SE3 dG = G[start].inverse() * G[end];
    const SE3 dE = E[start].inverse() * E[end];
    sec.err_m = dG.translation() - dE.translation();           // Eq. (10)
    sec.err_p_m = sec.err_m.norm();                            // Eq. (12)
    const EulerZYX eg = euler_zyx_from_quat(dG.quaternion());  // Eq. (11)
    const EulerZYX ee = euler_zyx_from_quat(dE.quaternion());
    sec.err_rad.roll_rad = wrap_angle_rad(eg.roll_rad - ee.roll_rad);
    sec.err_rad.pitch_rad = wrap_angle_rad(eg.pitch_rad - ee.pitch_rad);
    sec.err_rad.yaw_rad = wrap_angle_rad(eg.yaw_rad - ee.yaw_rad);

    // Covariates, Eq. (13).
    const double duration_s = ns_to_seconds(sec.t_end_ns - sec.t_start_ns);
    auto add = [&](const std::string& name, double v) {
      sec.covariate_names.push_back(name);
      sec.covariates.push_back(v);
    };
    add("v", duration_s > 0 ? sec.length_m / duration_s : kNaN);

    // Frames of the section: rows of `frames` whose time is in [start, end].
    std::vector<std::size_t> rows;
    if (frames)
      for (std::size_t r = 0; r < frames->t_ns.size(); ++r)
        if (frames->t_ns[r] >= sec.t_start_ns && frames->t_ns[r] <= sec.t_end_ns) rows.push_back(r);
    auto section_values = [&](const std::vector<double>& col) {
      std::vector<double> v;
      for (std::size_t r : rows) v.push_back(col[r]);
      return v;
    };
    auto attitude_sd_deg = [&](const char* column, int axis) {
      std::vector<double> a;
      if (const auto* col = frame_column(column)) {
        for (double x : section_values(*col))
          if (std::isfinite(x)) a.push_back(deg2rad(x));
      } else {
        for (std::size_t i = start; i <= end; ++i) {
          const EulerZYX e = euler_zyx_from_quat(G[i].quaternion());
          a.push_back(axis == 0 ? e.yaw_rad : axis == 1 ? e.pitch_rad : e.roll_rad);
        }
      }
      if (a.size() < 2) return kNaN;
      const Summary sum = summarize(unwrap(a));
      return rad2deg(sum.sd_sample);
    };
    add("h", attitude_sd_deg("yaw_deg", 0));
    add("pitch_sd_deg", attitude_sd_deg("pitch_deg", 1));
    add("roll_sd_deg", attitude_sd_deg("roll_deg", 2));
    if (frames) {
      const char* f_name = frame_column("inliers") ? "inliers" : "valid_depth_px";
      if (const auto* f = frame_column(f_name)) add("f", finite_mean(section_values(*f)));
      if (const auto* d = frame_column("mean_depth_m")) add("d", finite_mean(section_values(*d)));
      for (std::size_t k = 0; k < frames->names.size(); ++k) {
        const std::string& name = frames->names[k];
        if (name == "yaw_deg" || name == "pitch_deg" || name == "roll_deg" || name == f_name ||
            name == "mean_depth_m")
          continue;
        add(name, finite_mean(section_values(frames->columns[k])));
      }
    }
    sections.push_back(std::move(sec));
    start = end;
  }
  return sections;
}

SectionSummary summarize_sections(const std::vector<Section>& sections) {
  std::vector<double> p, x, y, z, roll, pitch, yaw;
  for (const auto& s : sections) {
    p.push_back(s.per_m(s.err_p_m));
    x.push_back(s.per_m(s.err_m.x()));
    y.push_back(s.per_m(s.err_m.y()));
    z.push_back(s.per_m(s.err_m.z()));
    roll.push_back(s.per_m(rad2deg(s.err_rad.roll_rad)));
    pitch.push_back(s.per_m(rad2deg(s.err_rad.pitch_rad)));
    yaw.push_back(s.per_m(rad2deg(s.err_rad.yaw_rad)));
  }
  return {summarize(p),    summarize(x),     summarize(y),  summarize(z),
          summarize(roll), summarize(pitch), summarize(yaw)};
}

Summary summarize_covariate(const std::vector<Section>& sections, std::string_view name) {
  std::vector<double> v;
  for (const auto& s : sections) {
    const double c = s.covariate(name);
    if (std::isfinite(c)) v.push_back(c);
  }
  return summarize(v);
}

}  // namespace driftlab::eval
