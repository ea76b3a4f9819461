#pragma once
// What `run`, `evaluate` and `demo` print about a run: each stage's report, the run's own
// lines, and the held-out evaluation's summary.

#include <string>

#include "pipeline/evaluation_report.h"
#include "pipeline/run_stages.h"

namespace confluent::app {

// One stage: frames computed and skipped, seconds, and up to 8 of its notes.
void PrintStageReport(const StageReport& report);

// A line of the run (flushed, so that it shows before the next stage's progress bar).
void PrintRunLine(const std::string& line);

// The evaluation's table, its warnings (stderr) and where its files are.
void PrintEvaluation(const EvaluationSummary& summary, const RunFolder& run);

}  // namespace confluent::app
