# Sourced by scripts/hil, scripts/wcet and scripts/test: which build flies aircraft NAME
# (aircraft/NAME.toml). The default aircraft (DEFAULT_AIRCRAFT in estimator-core/aircraft_name.rs)
# is the tree's own build in target/; another keeps its own, target/NAME, so the default's stays as
# it is (setting ESTIMATOR_AIRCRAFT for it would rebuild the tree). Expects `root` (the checkout).
default_aircraft=f16

# aircraft_build NAME: refuses an undescribed NAME (exit 2); sets `target` to the build's target
# directory and exports ESTIMATOR_AIRCRAFT and CARGO_TARGET_DIR for another aircraft (unsets them
# for the default one).
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
  fi
}
