#include "app/run_output.h"

#include <algorithm>
#include <cstdio>

namespace confluent::app {

void PrintStageReport(const StageReport& report) {
  std::printf("%-16s %6d computed %6d already done %9.1f s\n", report.stage.c_str(), report.computed, report.skipped,
              report.seconds);
  const std::size_t shown = std::min<std::size_t>(report.notes.size(), 8);
  for (std::size_t i = 0; i < shown; ++i) std::printf("    %s\n", report.notes[i].c_str());
  if (report.notes.size() > shown) std::printf("    ... %zu more\n", report.notes.size() - shown);
  std::fflush(stdout);
}

void PrintRunLine(const std::string& line) {
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

void PrintEvaluation(const EvaluationSummary& summary, const RunFolder& run) {
  std::printf("%s", SummaryTable(summary).c_str());
  for (const std::string& warning : summary.warnings)
    std::fprintf(stderr, "confluent evaluate: warning: %s\n", warning.c_str());
  std::printf("metrics: %s, plots: %s, report: %s\n", run.Path("metrics.json").c_str(), run.Path("plots").c_str(),
              run.Path("report.html").c_str());
  std::fflush(stdout);
}

}  // namespace confluent::app
