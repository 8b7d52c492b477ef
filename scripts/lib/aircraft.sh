# Sourced by scripts/hil, scripts/wcet and scripts/test: which build flies aircraft NAME
# (aircraft/NAME.toml). The default aircraft (DEFAULT_AIRCRAFT in estimator-core/aircraft_name.rs)
# is the tree's own build in target/; another keeps its own, target/NAME, so the default's stays as
# it is (setting ESTIMATOR_AIRCRAFT for it would rebuild the tree). Expects `root` (the checkout).
default_aircraft=f16

# aircraft_build NAME: refuses an undescribed NAME (exit 2); sets `target` to the build's target
# directory and exports ESTIMATOR_AIRCRAFT and CARGO_TARGET_DIR for another aircraft (unsets them
# for the default one). Another aircraft's first build starts from a copy of the default build's
# compiled dependencies (target/release, target/thumbv7em-none-eabihf) when those exist: only the
# crates that read the aircraft (estimator-core and the workspace crates above it) are compiled
# again, instead of every dependency (about 13 min on 2 cores). Cargo's fingerprints do not
# depend on the target directory; hil-sim's build script, which records it, reruns with
# ESTIMATOR_AIRCRAFT and CARGO_TARGET_DIR.
aircraft_build() {
  if [ ! -f "$root/aircraft/$1.toml" ]; then
    local known
    known="$(cd "$root/aircraft" && ls -- *.toml | sed 's/\.toml$//' | paste -sd' ' -)"
    echo "scripts/$(basename "$0"): --aircraft $1: no aircraft/$1.toml (described: $known; docs/aircraft.md)" >&2
    exit 2
  fi
  if [ "$1" = "$default_aircraft" ]; then
    unset ESTIMATOR_AIRCRAFT CARGO_TARGET_DIR
    target="$root/target"
  else
    export ESTIMATOR_AIRCRAFT="$1"
    target="$root/target/$1"
    export CARGO_TARGET_DIR="$target"
    local dir
    for dir in release thumbv7em-none-eabihf; do
      if [ ! -e "$target/$dir" ] && [ -d "$root/target/$dir" ]; then
        mkdir -p "$target"
        rm -rf "$target/$dir.seeding"
        cp -a "$root/target/$dir" "$target/$dir.seeding"
        # Not the default aircraft's binaries: only what cargo rebuilds or finds fresh.
        find "$target/$dir.seeding" -maxdepth 2 -type f ! -path '*/.fingerprint/*' ! -path '*/deps/*' \
          ! -path '*/build/*' -delete
        mv "$target/$dir.seeding" "$target/$dir"
      fi
    done
  fi
}
