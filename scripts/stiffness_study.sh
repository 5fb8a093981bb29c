#!/usr/bin/env bash
# The contact-stiffness study: what a softer contact (larger gamma*) or a longer DEM step (larger t* = dt/t_c)
# costs in accuracy, and what it saves.
# The resolved demo scene (data/scenes/pipeline_demo.toml, 30 x 120 x 30 d_p, 35 t_ref, the Table 1 physics)
# at gamma* = 1e-3 (the paper), 2e-3 and 4e-3, at a dilute and a dense <phi> (default 0.05 and 0.30), each
# run by Makefile.pipeline (PROFILE=demo) into its own OUT: the resolved run, its slip summary
# (study/resolved/phi<phi>.h5: mean over the filter window 15-35 t_ref, batch-means error, drift) and its
# filtered file (H per phi-bar bin on the filter widths and on the coarse grids' own operator).
# TSTARS (default 0.02, the scene's and the paper's 1/50) adds the DEM step to the configurations: a t* other than
# 0.02 runs in OUT/g<gamma*>_t<t*>_phi<phi> (contact.t_star set), 0.02 in OUT/g<gamma*>_phi<phi> as before.
# SEEDS (default 1, the demo scene's seed) adds realisations: a seed s other than 1 runs in
# OUT/g<gamma*>[_t<t*>]_s<s>_phi<phi> (particles.seed set); a second seed of the stiffest configuration measures how
# far two realisations lie apart by chaos alone, the scale against which the other rows are read.
# tools/stiffness_table.py then writes the table (slip, H, overlaps, contacts, cost) to OUT/stiffness.{txt,md}.
# Each configuration is an independent make: interrupted, it continues from its checkpoint (a second call
# reruns nothing that is complete). JOBS configurations run at once (default 2, one rank each).
# usage: scripts/stiffness_study.sh OUT [PHIS="0.05 0.30"] [GAMMAS="1e-3 2e-3 4e-3"] [TSTARS="0.02"] [SEEDS="1"] [JOBS=2]
# Exit status: 0 done; 1 a run or the table failed; 2 usage.
set -uo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
[ $# -ge 1 ] || { echo "usage: scripts/stiffness_study.sh OUT [PHIS=...] [GAMMAS=...] [TSTARS=...] [SEEDS=...] [JOBS=N]" >&2; exit 2; }
out=$1; shift
PHIS="0.05 0.30" GAMMAS="1e-3 2e-3 4e-3" TSTARS="0.02" SEEDS="1" JOBS=2
for kv in "$@"; do
  case $kv in
    PHIS=*|GAMMAS=*|TSTARS=*|SEEDS=*|JOBS=*) eval "${kv%%=*}=\"\${kv#*=}\"" ;;
    *) echo "stiffness_study.sh: unknown argument '$kv' (allowed: PHIS=, GAMMAS=, TSTARS=, SEEDS=, JOBS=)" >&2; exit 2 ;;
  esac
done
for s in $SEEDS; do
  [[ $s =~ ^[1-9][0-9]*$ ]] || { echo "stiffness_study.sh: SEEDS: '$s' is not a positive integer" >&2; exit 2; }
done
mkdir -p "$out" || exit 1
out=$(cd "$out" && pwd)
cd "$repo" || exit 1
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# densest, stiffest and finest-stepped first: the longest runs start first, so the JOBS slots stay full
configs=()
for phi in $(printf '%s\n' $PHIS | sort -gr); do
  for g in $(printf '%s\n' $GAMMAS | sort -g); do
    for t in $(printf '%s\n' $TSTARS | sort -g); do
      for s in $(printf '%s\n' $SEEDS | sort -g); do configs+=("$phi $g $t $s"); done
    done
  done
done
run_one() {
  local phi=$1 g=$2 t=$3 seed=$4 name="g$2" sets="contact.gamma_star=$2" dir
  if [ "$(awk -v t="$t" 'BEGIN { print (t + 0 == 0.02) }')" != 1 ]; then
    name+="_t$t" sets+=" contact.t_star=$t"
  fi
  if [ "$seed" != 1 ]; then name+="_s$seed" sets+=" particles.seed=$seed"; fi
  dir="$out/${name}_phi$phi"
  local phin; phin=$(make -s -f Makefile.pipeline PROFILE=demo PHIS="$phi" OUT="$dir" print-phi_list)
  make -s -f Makefile.pipeline PROFILE=demo PHIS="$phi" OUT="$dir" \
    GENERATE_SET="$sets" filter "$dir/study/resolved/phi$phin.h5" \
    > "$dir.make.log" 2>&1 && echo "stiffness_study.sh: gamma*=$g t*=$t seed=$seed phi=$phi done ($dir)" >&2 \
    || { echo "stiffness_study.sh: gamma*=$g t*=$t seed=$seed phi=$phi FAILED (log: $dir.make.log)" >&2; tail -20 "$dir.make.log" >&2; return 1; }
}
export -f run_one; export out
printf '%s\n' "${configs[@]}" | xargs -P "$JOBS" -L 1 bash -c 'run_one $0 $1 $2 $3' || exit 1
/usr/bin/python3 tools/stiffness_table.py "$out" -o "$out/stiffness" || exit 1
cat "$out/stiffness.txt"
