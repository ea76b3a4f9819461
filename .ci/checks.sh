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
step ./dev test --sanitize -L unit
step ./dev fuzz --seconds 30
step ./dev demo --preset tiny --out /tmp/confluent-ci-demo
step ./dev test
