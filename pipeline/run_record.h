#pragma once
// What `confluent run` checks before any work: the run folder's record of its inputs (run.json,
// written once, then compared on every resumption) and the scan it will animate.

#include <string>

#include <nlohmann/json.hpp>

#include "core/mesh.h"
#include "pipeline/run_stages.h"

namespace confluent {

// Writes RUN/run.json for `inputs` (with the command line's `options` and the program's
// `version`), or checks that an existing one was made from the same inputs: calibration, scan
// and correspondences (checksums), frame count, cameras, held-out cameras and frame rate.
// Throws InputError naming run.json when they differ.
void RecordRun(const RunInputs& inputs, const nlohmann::json& options, const std::string& version);

// Reads the scan, refusing before any work one the deformation cannot animate well: unreadable,
// non-finite, non-manifold or (unless `allow_open`) with holes. Throws InputError naming it.
Mesh ReadCheckedScan(const std::string& path, bool allow_open);

}  // namespace confluent
