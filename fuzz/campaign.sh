#!/usr/bin/env bash
# Runs fuzz targets one after another for SECONDS each (default 1800, issue 47's 30 minutes)
# with the issue's limits, and appends each run's final statistics to work/campaign.log.
#   bash campaign.sh [--seconds N] TARGET...
# Discovered inputs go to work/TARGET (git-ignored); findings to artifacts/TARGET.
set -u
cd "$(dirname "$0")"
seconds=1800
if [ "${1:-}" = "--seconds" ]; then seconds=$2; shift 2; fi
mkdir -p work
for t in "$@"; do
  mkdir -p "work/$t"
  RUSTC_BOOTSTRAP=1 cargo fuzz build "$t" >"work/$t.build.log" 2>&1 || { echo "$t: build failed (work/$t.build.log)" >>work/campaign.log; continue; }
  start=$(date -u +%FT%TZ)
  RUSTC_BOOTSTRAP=1 cargo fuzz run "$t" "work/$t" "corpus/$t" -- \
    -max_total_time="$seconds" -timeout=2 -rss_limit_mb=1024 -malloc_limit_mb=1024 \
    -print_final_stats=1 >"work/$t.log" 2>&1
  status=$?
  {
    echo "$t: started $start, ended $(date -u +%FT%TZ), exit $status"
    grep -E '^(stat::number_of_executed_units|stat::average_exec_per_sec|stat::peak_rss_mb)|^#[0-9]+ +DONE|^==[0-9]+== ERROR|^SUMMARY|Test unit written' "work/$t.log"
    echo
  } >>work/campaign.log
done
