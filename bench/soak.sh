#!/usr/bin/env bash
# Soak of `dancegen serve` (issue 47): 20 clients on loopback for SECONDS (default 1800, 30
# minutes) — uploads, status polls, progress streams, cancels and deletes — then requests
# served, errors, p50/p99 latency, peak RSS (and whether it grew after the first five
# minutes), open file descriptors and jobs lost. The same test runs for 60 s in the suite.
#   bash bench/soak.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-1800}
DANCEGEN_SOAK_SECONDS=$seconds cargo test -p dancegen-cli --test cli_soak -- --nocapture 2>&1 \
  | tee /dev/stderr | grep '^soak: '
