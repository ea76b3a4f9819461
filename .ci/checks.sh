#!/usr/bin/env bash
# What CI runs inside the brand-new root (.ci/run); each step prints its time.
set -euo pipefail
cd "$(dirname "$0")/.."
step() {
  local started=$(date +%s)
  echo "== ci: $*" >&2
  "$@"
  echo "== ci: $* took $(( $(date +%s) - started )) s" >&2
}
# The unit tests under ASan+UBSan, less the suites that run for minutes under the sanitizers
# (whole-body Ceres fits, checkerboard calibrations, real footage: 20 s to 8 min per test there,
# about 25 min together on 2 cores). They run unsanitized in ./dev test below, and sanitized
# in `./dev test --sanitize` by hand. ctest runs one process per GoogleTest suite
# (cmake/list_gtest_suites.cmake), so these are suite names.
# The plate-free silhouette suites (issue 20) are among them: 1 to 7.5 min per test sanitized,
# and SilhouettesCli's runs on a capture; so are LandmarkLimbs' tracker test (3.2 min sanitized,
# 24 s unsanitized) and LimbSearchRepeat's three (52-97 s each sanitized, 5-11 s unsanitized).
heavy='^(SambaRealMotion|TrackerResume|GirthInflation|SilhouetteFit|SkirtFit|LimbRecovery|LimbSearchRepeat|LandmarkLimbs|ScanCorrespondence|ScanRegistration|Calibrate|RealSilhouettes|RealCheckerboard|CorrespondencePlacement|TemplateMotion|TrackCommand|PlateFree|SilhouettesCli)$'
step ./dev test --sanitize -L unit -E "$heavy"
step ./dev fuzz --seconds 15 --seed 1
# The release build (its own step, for its time). The demo itself runs in ./dev test below
# (DemoCommand.TinyPresetRunsThePipelineAndReports runs `confluent demo --preset tiny`).
step ./dev build
# The motion suite's tiny variant: fails when a capture falls below bench/suite_floors_tiny.json.
step ./dev suite --preset tiny --check --out /tmp/confluent-ci-suite
step ./dev test
