# Sourced by the closure experiments' scripts (closure_drift.sh, closure_wide_filter.sh, figure3_box.sh): one coarse
# run of their matrix, and the profile's settings they share with the pipeline.
# coarse_run RUN PHI ALPHA SEED [cgd-coarse options...]: cgd-coarse of $repo/$base_scene with the caller's array
# $coarse_sets (its --set options, given first), then that solids fraction, seed and parcel size on cells of $dx d_p,
# then the options; niceness $nice_level, through the launcher array $launcher (empty: one rank) -> RUN (log RUN.log).
# A run whose summary.h5 exists is kept; one killed before its end (its checkpoint.h5 there, no summary.h5) is
# continued from its checkpoint (cgd-coarse --restart, the scene it was started with: a changed window or model is not
# applied to it; log RUN.restart.log), and started again only when that restart fails or writes no summary.h5 (a run
# that diverges is so run twice); a failed run is reported through the caller's say() and left out (status 0), so
# that one failure does not stop the matrix.
# cgd_coarse ARGS...: the caller's $build/cgd-coarse at niceness $nice_level through its launcher array
cgd_coarse() { nice -n "$nice_level" "${launcher[@]}" "$build/cgd-coarse" "$@"; }
coarse_run() {
  local run=$1 phi=$2 alpha=$3 seed=$4
  shift 4
  [ -f "$run/summary.h5" ] && return 0
  if [ -f "$run/checkpoint.h5" ]; then
    say "$(basename "$run") (continued from its checkpoint)"
    cgd_coarse --restart --quiet -o "$run" > "$run.restart.log" 2>&1 &&
      [ -f "$run/summary.h5" ] && return 0
    say "$(basename "$run"): the restart failed or wrote no summary.h5 (log $run.restart.log); run again from the start"
  fi
  rm -rf "$run"
  say "$(basename "$run")"
  cgd_coarse "$repo/$base_scene" --quiet "${coarse_sets[@]}" \
    --set particles.solids_fraction="$phi" --set particles.seed="$seed" --set fluid.dx_over_dp="$dx" \
    --set particles.parcel_size="$alpha" "$@" -o "$run" > "$run.log" 2>&1 ||
    { say "$(basename "$run") failed (log $run.log)"; return 0; }
}

# The profile's settings as the pipeline gives them, through the caller's mk() (make of Makefile.pipeline with its
# PROFILE). A make that fails returns 1 (the callers' set -e stops there) rather than giving no settings.
# profile_words NAME ARRAY: the make variable NAME split into words -> the array ARRAY (e.g. FILTER_ARGS_LINE:
# cgd-filter's options; FIT_ARGS: cgd-fit's).
profile_words() {
  local line
  line=$(cd "$repo" && mk "print-$1") || return 1
  read -r -a "$2" <<< "$line"
}
# profile_coarse_sets: COARSE_SET as --set options (the half profile's box, gamma* and the coarse runs' 40-80 t_ref
# window; empty for the paper's, whose base scene is its box) -> the array coarse_sets.
profile_coarse_sets() {
  local s words
  profile_words COARSE_SET words || return 1
  coarse_sets=()
  for s in "${words[@]}"; do coarse_sets+=(--set "$s"); done
}
# profile_phi_sets PHI: PHI_SET_<PHI> as --set options (e.g. the half box's dense runs' gamma* = 1e-3 and t* = 0.05;
# PHI spelled as the run directories, two decimals) -> the array phi_sets, given after the others as the pipeline does.
profile_phi_sets() {
  local s words
  profile_words "PHI_SET_$1" words || return 1
  phi_sets=()
  for s in "${words[@]}"; do phi_sets+=(--set "$s"); done
}
