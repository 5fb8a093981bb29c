# Sourced by the closure experiments' scripts (closure_drift.sh, closure_wide_filter.sh, figure3_box.sh): one coarse run of their matrix.
# coarse_run RUN PHI ALPHA SEED [cgd-coarse options...]: cgd-coarse of $repo/$base_scene with the caller's array
# $coarse_sets (its --set options, given first), then that solids fraction, seed and parcel size on cells of $dx d_p,
# then the options; niceness $nice_level, through the launcher array $launcher (empty: one rank) -> RUN (log RUN.log).
# A run whose summary.h5 exists is kept; a failed run is reported through the caller's say() and left out (status 0),
# so that one failure does not stop the matrix.
coarse_run() {
  local run=$1 phi=$2 alpha=$3 seed=$4
  shift 4
  [ -f "$run/summary.h5" ] && return 0
  rm -rf "$run"
  say "$(basename "$run")"
  nice -n "$nice_level" "${launcher[@]}" "$build/cgd-coarse" "$repo/$base_scene" --quiet "${coarse_sets[@]}" \
    --set particles.solids_fraction="$phi" --set particles.seed="$seed" --set fluid.dx_over_dp="$dx" \
    --set particles.parcel_size="$alpha" "$@" -o "$run" > "$run.log" 2>&1 ||
    { say "$(basename "$run") failed (log $run.log)"; return 0; }
}

# The profile's settings as the pipeline gives them to its coarse runs, as --set options (through the caller's mk(),
# make of Makefile.pipeline with its PROFILE):
# profile_coarse_sets: COARSE_SET (the half profile's box and gamma*; empty for the paper's, whose base scene is its
# box) -> the array coarse_sets.
profile_coarse_sets() {
  local s set
  read -r -a set <<< "$(cd "$repo" && mk print-COARSE_SET)"
  coarse_sets=()
  for s in "${set[@]}"; do coarse_sets+=(--set "$s"); done
}
# profile_phi_sets PHI: PHI_SET_<PHI> (e.g. the half box's dense runs' gamma* = 1e-3 and t* = 0.05; PHI spelled as the
# run directories, two decimals) -> the array phi_sets, to be given after the others as the pipeline does.
profile_phi_sets() {
  local s set
  read -r -a set <<< "$(cd "$repo" && mk "print-PHI_SET_$1")"
  phi_sets=()
  for s in "${set[@]}"; do phi_sets+=(--set "$s"); done
}
