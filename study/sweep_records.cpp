#include "study/sweep_records.hpp"

namespace driftlab::study {

std::string sweep_files_reference_markdown() {
  using record_json::fields_markdown;
  using record_json::fields_of;
  std::string md;
  auto section = [&](const char* title, const char* intro, std::string table) {
    md += std::string("\n## ") + title + "\n\n" + intro + "\n\n" + table;
  };
  section("A sweep's summary/metrics.json",
          "Written by `driftlab sweep merge`. NAME stands for an algorithm, a run metric, a "
          "paired metric, a job or a point; their order is the merge's.",
          fields_markdown(fields_of<SweepSummaryRecord>()));
  section("A sweep's sweep.json", "Written by `driftlab sweep plan`: what was planned.",
          fields_markdown(fields_of<SweepInfoRecord>()));
  section("A sweep's manifest.jsonl", "Written by `driftlab sweep plan`: one job per line.",
          fields_markdown(fields_of<ManifestJobRecord>()));
  section("A sweep's runs/ID/job.json",
          "Written last into a finished job's run folder: its completion marker.",
          fields_markdown(fields_of<JobMarkerRecord>()));
  section("A sweep's failed/ID.json", "Written for a job that ended without its marker.",
          fields_markdown(fields_of<FailureRecord>()));
  section("A sweep's slurm/slurm.json", "Written by `driftlab sweep slurm-script`.",
          fields_markdown(fields_of<SlurmRecord>()));
  return md;
}

}  // namespace driftlab::study
