#!/usr/bin/env bash
# Runs every fuzz target for a bounded time and fails on a finding.
#
#   fuzz/run.sh [SECONDS_PER_TARGET] [TARGET...]
#
# Default: 40 s per target (four targets, under three minutes plus the
# build). A longer campaign by hand: `fuzz/run.sh 3600`. Needs the dated
# nightly of xtensa/nightly (the one the image is built with) and cargo-fuzz
# (`cargo install cargo-fuzz --locked`).
#
# Corpora grow in fuzz/corpus/<target>/ (not committed; kept between runs
# on one machine) from the committed seeds in fuzz/seeds/<target>/. A
# finding (panic, overflow, failed assertion, crash, leak, timeout) is
# written to fuzz/artifacts/<target>/ and makes this script exit non-zero;
# reproduce it with `cargo +$(cat xtensa/nightly) fuzz run <target> <artifact>`.
set -euo pipefail
cd "$(dirname "$0")/.."
nightly="+$(cat xtensa/nightly)"

secs=${1:-40}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(protocol_parse telemetry_roundtrip serial_loop settings_decode)
fi

cargo "$nightly" fuzz build

status=0
summary=()
for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus/$t"
  seeds=()
  [ -d "fuzz/seeds/$t" ] && seeds=("fuzz/seeds/$t")
  dict=()
  case $t in protocol_parse | serial_loop) dict=(-dict=fuzz/protocol.dict) ;; esac
  log="fuzz/artifacts/$t.log"
  mkdir -p "fuzz/artifacts/$t"
  printf '\n-- fuzz %s for %ss\n' "$t" "$secs"
  # -timeout: one input taking over 10 s is a hang (the loop must never block)
  if cargo "$nightly" fuzz run "$t" "fuzz/corpus/$t" "${seeds[@]}" -- \
    -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 "${dict[@]}" >"$log" 2>&1; then
    result=ok
  else
    result=FINDING
    status=1
    tail -n 40 "$log"
  fi
  runs=$(grep -Eo 'Done [0-9]+ runs' "$log" | grep -Eo '[0-9]+' || echo '?')
  cov=$(grep -Eo 'cov: [0-9]+' "$log" | tail -n 1 | grep -Eo '[0-9]+' || echo '?')
  corpus=$(find "fuzz/corpus/$t" -type f | wc -l)
  summary+=("$(printf '%-20s %-8s %10s execs  cov %5s  corpus %5s' "$t" "$result" "$runs" "$cov" "$corpus")")
done

printf '\n== fuzz summary (%ss per target)\n' "$secs"
printf '%s\n' "${summary[@]}"
exit $status
