#!/usr/bin/env bash
# e2e: the exit statuses of cgd-generate and cgd-coarse agree with each other and with the shell:
#  * -o naming an existing file is bad input: exit 2, a message naming it, nothing written (the file is
#    left as it was and no directory appears beside it);
#  * SIGINT and SIGTERM write a checkpoint and end the run with 130 and 143 (128 + signal, what a shell
#    reports for a process the signal ended), and --restart continues the interrupted run to DONE.
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
scene=$source_dir/data/scenes/pipeline_demo.toml
small=(--set 'domain.size_dp=[20,80,20]' --set fluid.dx_over_dp=5 --set run.dump_interval_tref=0.25
       --set run.sampling_start_tref=0.25 --quiet)

for tool in cgd-generate cgd-coarse; do
  bin=$binary_dir/$tool
  # -o names a regular file (one with content, one empty)
  mkdir "$tmp/o"
  for content in "not a run directory" ""; do
    printf '%s' "$content" >"$tmp/o/file"
    timeout 120 "$bin" "$scene" "${small[@]}" --set run.end_time_tref=0.5 -o "$tmp/o/file" >"$tmp/out" 2>"$tmp/err"
    status=$?
    if [ "$status" -eq 2 ] && grep -qF -- "-o $tmp/o/file: exists and is not a directory" "$tmp/err" &&
       [ "$(cat "$tmp/o/file")" = "$content" ] && [ "$(ls -A "$tmp/o")" = file ]; then
      echo "ok   $tool -o FILE (${#content} bytes): exit 2, $(head -n 1 "$tmp/err")"
    else
      fail "$tool -o FILE (${#content} bytes): exit $status, stderr: $(cat "$tmp/err"); beside it: $(ls -A "$tmp/o" | tr '\n' ' ')"
    fi
  done
  rm -rf "$tmp/o" "$tmp/out" "$tmp/err"

  # SIGINT -> 130, SIGTERM -> 143; a run far too long to finish while the test waits
  for signal in INT TERM; do
    expected=$([ "$signal" = INT ] && echo 130 || echo 143)
    dir=$tmp/$tool-$signal
    "$bin" "$scene" "${small[@]}" --set run.end_time_tref=100 -o "$dir" >"$dir.out" 2>"$dir.err" &
    pid=$!
    # Signal on what the run wrote, not after a time: the first snapshot exists once the loop runs (the
    # handlers are installed before it). The loop's limit only guards against a hang.
    for _ in $(seq 1 12000); do
      [ -f "$dir/snapshots/snap_000000000.h5" ] && break
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.01
    done
    kill -s "$signal" "$pid"
    wait "$pid"
    status=$?
    if [ "$status" -eq "$expected" ] && [ -f "$dir/checkpoint.h5" ] && [ ! -f "$dir/DONE" ] &&
       grep -q "run interrupted: SIG$signal at step" "$dir.err"; then
      echo "ok   $tool SIG$signal: exit $status, $(grep 'run interrupted' "$dir.err")"
    else
      fail "$tool SIG$signal: exit $status (expected $expected); checkpoint $(ls "$dir/checkpoint.h5" 2>&1); stderr: $(cat "$dir.err")"
    fi
  done
  # the interrupted run continues (to a shorter end: the scene keys a restart may change)
  dir=$tmp/$tool-TERM
  if timeout 250 "$bin" "$scene" "${small[@]}" --set run.end_time_tref=0.5 --restart -o "$dir" >"$dir.restart" 2>&1 &&
     [ -f "$dir/DONE" ]; then
    echo "ok   $tool: the interrupted run continues with --restart to DONE"
  else
    # an end before the checkpoint is refused: then the run was interrupted later than 0.5 t_ref
    grep -q "before the checkpoint" "$dir.restart" && echo "ok   $tool: (interrupted after 0.5 t_ref; restart not tried)" ||
      fail "$tool --restart after SIGTERM: $(cat "$dir.restart")"
  fi
done

[ "$failures" -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "all exit-status checks passed"
