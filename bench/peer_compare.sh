#!/usr/bin/env bash
# The DEM peer benchmark in one invocation: cgd against Debian's LAMMPS on this machine, same
# particles, contact law, box and step count (the peer cases of shared/peers/README.md).
# usage: bench/peer_compare.sh [cases=s10,l10,l30] [ranks=1,2] [steps=2000]
#   e.g. bench/peer_compare.sh s10 1,2 200
# Needs: lmp (scripts/setup.sh --bench) and build/bench/cgd-bench-dem (scripts/setup.sh).
# Environment: CGD_PEERS_DIR (default: ../shared/peers beside the repository), PEER_WORK (data and
# logs, default /tmp/cgd-peers), CGD_BENCH_DEM (default: build/bench/cgd-bench-dem).
# Prints, per case and rank count: particle-steps per second per core of each code (from the
# codes' own loop timers, warm-up excluded), their ratio, peak RSS per particle (summed over ranks,
# measured with /usr/bin/time around each rank) and the speed-up from 1 rank.
# Exit status: 0 all runs done; 1 a run failed (marked in the table); 2 bad arguments or missing tools.
set -uo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
peers=${CGD_PEERS_DIR:-$repo/../shared/peers}
export PEER_WORK=${PEER_WORK:-/tmp/cgd-peers}
cgd_bench=${CGD_BENCH_DEM:-$repo/build/bench/cgd-bench-dem}
neq=200  # warm-up steps before the timed run, as in shared/peers/bench.sh

say() { echo "peer_compare.sh: $*" >&2; }
usage() { sed -n '4,5s/^# \{0,1\}//p' "${BASH_SOURCE[0]}" >&2; exit 2; }

case ${1:-} in -h|--help) usage ;; esac
IFS=, read -r -a cases <<< "${1:-s10,l10,l30}"
IFS=, read -r -a ranks <<< "${2:-1,2}"
steps=${3:-2000}
for c in "${cases[@]}"; do
  case $c in s10|s30|l10|l30) ;; *) say "bad case '$c' (allowed: s10 s30 l10 l30)"; usage ;; esac
done
for n in "${ranks[@]}" "$steps"; do
  [[ $n =~ ^[1-9][0-9]*$ ]] || { say "bad number '$n' (ranks and steps are positive integers)"; usage; }
done

# ---- tools ------------------------------------------------------------------------------------
[ -f "$peers/in.lammps" ] && [ -x "$peers/make_data.sh" ] ||
  { say "peer benchmark files not found in '$peers' (set CGD_PEERS_DIR to the shared/peers folder)"; exit 2; }
peers=$(cd "$peers" && pwd)
command -v lmp >/dev/null || { say "LAMMPS (lmp) is not installed: run 'bash scripts/setup.sh --bench'"; exit 2; }
[ -x /usr/bin/time ] || { say "/usr/bin/time is missing: run 'bash scripts/setup.sh'"; exit 2; }
[ -x "$cgd_bench" ] || { say "cgd's benchmark driver '$cgd_bench' is missing: build it with 'bash scripts/setup.sh'"; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$PEER_WORK/logs"

# Run "$@" on $1 ranks (directly for 1 rank, as bench.sh does), each rank under /usr/bin/time
# appending its peak RSS (KiB) as one line to $rss_file (O_APPEND: the ranks' lines do not mix).
rss_file=$PEER_WORK/logs/rss.$$
launch() {
  local np=$1; shift
  rm -f "$rss_file"
  local mpi=()
  [ "$np" -gt 1 ] && mpi=(mpirun --allow-run-as-root --oversubscribe -np "$np")
  "${mpi[@]}" /usr/bin/time -a -o "$rss_file" -f %M "$@"
}
rss_total_kib() { awk '/^[0-9]+$/ {s += $1; n++} END {if (n) print s; else print "nan"}' "$rss_file" 2>/dev/null; }

# Result fields per run, keyed by code_case_np: N, loop_s, ps (particle-steps/s/core), rss (KiB),
# own (cgd's own count of bytes per particle in its arrays).
declare -A N loop ps rss own
failed=0

run_lammps() {  # same invocation as shared/peers/bench.sh, with /usr/bin/time around each rank
  local cs=$1 np=$2 key=lammps_$1_$2 log=$PEER_WORK/logs/lammps_$1_np$2.log
  rm -f "$log"
  (cd "$peers" && launch "$np" lmp -in in.lammps -var data "$PEER_WORK/data/$cs.data" -var neq $neq \
     -var nsteps "$steps" -log "$log" -screen none) > "$PEER_WORK/logs/lammps_$1_np$2.out" 2>&1
  local line
  line=$(grep '^Loop time' "$log" 2>/dev/null | tail -n 1)
  if [ -z "$line" ]; then say "LAMMPS $cs on $np ranks failed: see $log and ${log%.log}.out"; failed=1; return; fi
  # "Loop time of T on P procs for S steps with N atoms"
  loop[$key]=$(awk '{print $4}' <<< "$line")
  N[$key]=$(awk '{print $(NF-1)}' <<< "$line")
  ps[$key]=$(awk -v n="${N[$key]}" -v s="$steps" -v t="${loop[$key]}" -v p="$np" 'BEGIN {printf "%.4g", n*s/t/p}')
  rss[$key]=$(rss_total_kib)
}

field() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<< "$2"; }  # value of NAME= in a result line
run_cgd() {  # prints one line: cgd CASE N=... ranks=... loop_s=... ps_per_s_per_core=... bytes_per_particle=...
  local cs=$1 np=$2 key=cgd_$1_$2 out=$PEER_WORK/logs/cgd_$1_np$2.out
  launch "$np" "$cgd_bench" --data "$PEER_WORK/data/$cs.data" --neq $neq --steps "$steps" > "$out" 2>&1
  local status=$? line
  line=$(grep -m 1 "^cgd $cs " "$out")
  if [ $status -ne 0 ] || [ -z "$line" ]; then say "cgd $cs on $np ranks failed (exit $status): see $out"; failed=1; return; fi
  N[$key]=$(field N "$line"); loop[$key]=$(field loop_s "$line"); ps[$key]=$(field ps_per_s_per_core "$line")
  own[$key]=$(field bytes_per_particle "$line")
  rss[$key]=$(rss_total_kib)
}

# ---- runs -------------------------------------------------------------------------------------
for cs in "${cases[@]}"; do
  case $cs in s*) "$peers/make_data.sh" small ;; l*) "$peers/make_data.sh" large ;; esac >&2 ||
    { say "make_data.sh failed for $cs"; exit 1; }
  for np in "${ranks[@]}"; do
    say "$cs, $np rank(s), $steps steps: LAMMPS"
    run_lammps "$cs" "$np"
    say "$cs, $np rank(s), $steps steps: cgd"
    run_cgd "$cs" "$np"
    l=${N[lammps_${cs}_$np]:-} c=${N[cgd_${cs}_$np]:-}
    [ -z "$l" ] || [ -z "$c" ] || [ "$l" = "$c" ] ||
      { say "WARNING: $cs on $np ranks: particle counts differ (LAMMPS $l, cgd $c)"; failed=1; }
  done
done
rm -f "$rss_file"

# ---- table ------------------------------------------------------------------------------------
ratio() { awk -v a="$1" -v b="$2" 'BEGIN {if (a == "" || b == "" || a == "nan" || b == "nan" || b == 0) print "-"; else printf "%.3g", a/b}'; }
per_particle() { awk -v k="$1" -v n="$2" 'BEGIN {if (k == "" || k == "nan" || n == "" || n == 0) print "-"; else printf "%.0f", k*1024/n}'; }
or_dash() { [ -n "${1:-}" ] && echo "$1" || echo "-"; }

echo
echo "DEM peer benchmark, $(date -u +%Y-%m-%d), $(hostname), $(nproc) cores, $steps timed steps after $neq warm-up"
echo "(ps/s/core: particle-steps per second per core from each code's loop timer; RSS: peak resident set, summed over ranks)"
echo
row() { printf '| %-4s | %7s | %5s | %16s | %13s | %10s | %17s | %14s | %16s | %15s | %12s |\n' "$@"; }
row case N ranks "LAMMPS ps/s/core" "cgd ps/s/core" cgd/LAMMPS "LAMMPS RSS B/part" "cgd RSS B/part" "cgd arrays B/part" \
  "LAMMPS speed-up" "cgd speed-up"
row ---- ------- ----- ---------------- ------------- ---------- ----------------- -------------- ---------------- \
  --------------- ------------
for cs in "${cases[@]}"; do
  for np in "${ranks[@]}"; do
    l=lammps_${cs}_$np c=cgd_${cs}_$np
    row "$cs" "$(or_dash "${N[$l]:-${N[$c]:-}}")" "$np" "$(or_dash "${ps[$l]:-}")" "$(or_dash "${ps[$c]:-}")" \
      "$(ratio "${ps[$c]:-}" "${ps[$l]:-}")" \
      "$(per_particle "${rss[$l]:-}" "${N[$l]:-}")" "$(per_particle "${rss[$c]:-}" "${N[$c]:-}")" "$(or_dash "${own[$c]:-}")" \
      "$(ratio "${loop[lammps_${cs}_1]:-}" "${loop[$l]:-}")" "$(ratio "${loop[cgd_${cs}_1]:-}" "${loop[$c]:-}")"
  done
done
echo
echo "speed-up: loop time on 1 rank / loop time on this many ranks (1 = no gain). Logs: $PEER_WORK/logs"
[ $failed -eq 0 ] || { say "some runs failed (marked '-'); see the logs named above"; exit 1; }
