// The one reader of a run's metrics.json: what it accepts from older files, what it refuses.
#include "record/run_record.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace driftlab::record {
namespace {

std::string read_error(const nlohmann::json& j) {
  try {
    run_record_from_json(j, "run/metrics.json");
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

// A file from before `metrics_version` (version 1: the same keys) reads, and so does a run
// without sensors whose block was written as null.
TEST(RunRecord, ReadsAFileWithoutAVersionAsVersionOne) {
  const auto j = nlohmann::json::parse(R"({
    "version": "0.1.0", "seed": 3, "scenario": "river_crossing", "sensors": null,
    "timing": {"total_s": 1.5},
    "algorithms": {"sparse": {"algorithm": "sparse", "ape": {"trans_m": {"rmse": 0.25}}}},
    "warnings": []})");
  const RunRecord r = run_record_from_json(j, "old/metrics.json");
  EXPECT_EQ(r.metrics_version, 1);
  EXPECT_EQ(r.seed, 3u);
  EXPECT_FALSE(r.sensors.has_value());
  EXPECT_DOUBLE_EQ(r.algorithms.at("sparse").evaluation.ape.trans_m.rmse, 0.25);
}

TEST(RunRecord, RefusesANewerVersionASweepSummaryAndAWrongType) {
  EXPECT_EQ(read_error(nlohmann::json::parse(R"({"metrics_version": 3})")),
            "run/metrics.json: metrics_version 3 was written by a newer driftlab; this one "
            "reads versions 1 to 2");
  EXPECT_EQ(read_error(nlohmann::json::parse(R"({"sweep": {}, "algorithms": {}})")),
            "run/metrics.json: a sweep's merged metrics (it has `sweep`), expected a run's "
            "metrics.json");
  EXPECT_EQ(read_error(nlohmann::json::parse(R"({"algorithms": {"pnp": {"track": {"n": 1.5}}}})")),
            "run/metrics.json: algorithms.pnp.track.n: got 1.5, expected a whole number >= 0");
}

// What a run writes, read back, writes the same bytes (every block of the record present).
TEST(RunRecord, WritesWhatItReadsByteForByte) {
  RunRecord r;
  r.version = "0.1.0";
  r.scenario = "basin_exp3";
  r.sensors = SensorsRecord{ImuRecord{10, 200}, std::nullopt, GpsRecord{}, std::nullopt};
  r.timing.vo_ms_per_frame = std::map<std::string, double>{{"pnp", 12.5}};
  AlgorithmRecord& a = r.algorithms["pnp_ned_kf"];
  a.evaluation.algorithm = "pnp_ned_kf";
  a.evaluation.basin_overhead = eval::BasinReferenceRecord{{}, "overhead camera", 40};
  a.filter = std::map<std::string, std::int64_t>{{"nonfinite_guards", 0}};
  a.vs_raw_vo = VsRawVoRecord{"pnp", "ape.trans_m.rmse", 0.1, 0.2, 0.5, true};
  r.external_vo = std::map<std::string, ExternalVoRecord>{{"mine", {}}};
  const std::string text = metrics_text(r);
  const RunRecord back = run_record_from_json(nlohmann::json::parse(text), "m.json");
  EXPECT_EQ(metrics_text(back), text);
  // The GPS without a fix: its HDOP null, read back as not a number.
  EXPECT_NE(text.find("\"mean_hdop_with_fix\": null"), std::string::npos);
  EXPECT_TRUE(std::isnan(back.sensors->gps->mean_hdop_with_fix));
}

// A track never evaluated (a filter on a dataset without ground truth) keeps only what it has.
TEST(RunRecord, ATrackNeverEvaluatedIsWrittenWithoutEvaluationKeys) {
  RunRecord r;
  r.algorithms["sparse_ca"].filter = std::map<std::string, std::int64_t>{{"nonfinite_guards", 0}};
  const nlohmann::json j = nlohmann::json::parse(metrics_text(r));
  EXPECT_EQ(j["algorithms"]["sparse_ca"].dump(), R"({"filter":{"nonfinite_guards":0}})");
  const RunRecord back = run_record_from_json(j, "m.json");
  EXPECT_EQ(metrics_text(back), metrics_text(r));
}

}  // namespace
}  // namespace driftlab::record
