# Sourced by scripts/hil, scripts/wcet, scripts/e2e-small, scripts/test, scripts/build-estimator,
# scripts/calibrate and scripts/analysis: which build flies aircraft NAME
# (aircraft/NAME.toml), and the analyses' independent test flights of it. The default aircraft (DEFAULT_AIRCRAFT in estimator-core/aircraft_name.rs)
# is the tree's own build in target/; another keeps its own, target/NAME, so the default's stays as
# it is (setting ESTIMATOR_AIRCRAFT for it would rebuild the tree). Expects `root` (the checkout).
default_aircraft=f16

# seed_build DIR: target/NAME/DIR (`target`) starts from the default build's target/DIR (what
# cargo reuses of its profile directories: see below), when the one is missing and the other
# exists, so that another aircraft's first build compiles only the crates that read the aircraft
# (estimator-core and the workspace crates above it), not every dependency again as in an empty
# target directory. The default's holds every dependency the
# scripts' builds need, once: they all resolve the same features (scripts/check-features). Cargo's
# fingerprints do not depend on the target directory; hil-sim's build script, which records it,
# reruns with ESTIMATOR_AIRCRAFT. Held under a lock of its own (two scripts seeding the same
# aircraft) and under cargo's locks of the source (no build writes it mid-copy); a failed copy
# leaves no target/NAME/DIR behind.
seed_build() {
  local src="$root/target/$1" dst="$target/$1"
  if [ -e "$dst" ] || [ ! -d "$src" ]; then return 0; fi
  mkdir -p "$target"
  (
    exec {mine}>"$target/.seeding.lock"
    flock "$mine"
    [ -e "$dst" ] && exit 0
    local lock fd
    while IFS= read -r lock; do
      exec {fd}>"$lock"
      flock "$fd"
    done < <(find "$src" -maxdepth 2 -name .cargo-lock)
    rm -rf "$dst.seeding"
    # Only what cargo reuses, of each profile's directory (DIR itself, as target/release, or the
    # ones under a target triple's): its fingerprints, the build scripts' outputs and the compiled
    # crates (rlib, rmeta, a, so and their .d); not the binaries, examples or anything else a
    # command left there, nor the test and binary executables in deps/ (they link estimator-core,
    # so are rebuilt anyway).
    local profile part
    while IFS= read -r profile; do
      mkdir -p "$dst.seeding/$profile"
      for part in .fingerprint build deps; do
        if [ -d "$src/$profile/$part" ]; then cp -a "$src/$profile/$part" "$dst.seeding/$profile/$part"; fi
      done
      if [ -d "$dst.seeding/$profile/deps" ]; then
        find "$dst.seeding/$profile/deps" -maxdepth 1 -type f \
          ! -name '*.rlib' ! -name '*.rmeta' ! -name '*.a' ! -name '*.so' ! -name '*.d' -delete
      fi
    done < <(cd "$src" && if [ -d .fingerprint ]; then echo .; else find . -mindepth 2 -maxdepth 2 -name .fingerprint -type d -printf '%h\n'; fi)
    [ -d "$dst.seeding" ] || exit 0  # no profile built there yet: nothing to seed
    mv -T "$dst.seeding" "$dst"
  )
}

# aircraft_target NAME: refuses an undescribed NAME (exit 2); sets `target` to its build's target
# directory (for reading its binaries: nothing is built or exported).
aircraft_target() {
  if [ ! -f "$root/aircraft/$1.toml" ]; then
    local known
    known="$(cd "$root/aircraft" && ls -- *.toml | sed 's/\.toml$//' | paste -sd' ' -)"
    echo "${0#"$root"/}: --aircraft $1: no aircraft/$1.toml (described: $known; docs/aircraft.md)" >&2
    exit 2
  fi
  if [ "$1" = "$default_aircraft" ]; then target="$root/target"; else target="$root/target/$1"; fi
}

# analysis_binaries NAME TOOL...: aircraft_target NAME, `bin` its release build's directory, and a
# refusal naming how to build it when a TOOL (hil-sim, trainer) is not there (the analyses' check).
analysis_binaries() {
  local name="$1" b
  shift
  aircraft_target "$name"
  bin="$target/release"
  for b in "$@"; do
    [ -x "$bin/$b" ] || {
      echo "${0#"$root"/}: no $bin/$b: build $name's release build first (the script's header)" >&2
      exit 2
    }
  done
}

# analysis_aircraft NAME...: the AIRCRAFT arguments of an analysis script, every one checked
# (described, its hil-sim and trainer built) before any aircraft's work starts; -h/--help prints
# the script's header, another option is refused with its usage line.
analysis_aircraft() {
  local name
  for name in "$@"; do
    case "$name" in
      -h|--help) awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$0"; exit 0 ;;
      -*) echo "${0#"$root"/}: unknown option $name" >&2; echo "usage: ${0#"$root"/} [AIRCRAFT ...]" >&2; exit 2 ;;
    esac
    analysis_binaries "$name" hil-sim trainer
  done
}

# aircraft_build NAME: aircraft_target, and exports ESTIMATOR_AIRCRAFT and CARGO_TARGET_DIR for
# another aircraft (unsets them for the default one). Another aircraft's first build starts from
# the default's (seed_build).
aircraft_build() {
  aircraft_target "$1"
  if [ "$1" = "$default_aircraft" ]; then
    unset ESTIMATOR_AIRCRAFT CARGO_TARGET_DIR
  else
    export ESTIMATOR_AIRCRAFT="$1" CARGO_TARGET_DIR="$target"
    seed_build release
    seed_build thumbv7em-none-eabihf
    seed_build firmware  # the flight image's host side: its build scripts and proc macros
  fi
}

# description_value NAME SECTION KEY: prints `[SECTION] KEY` of aircraft/NAME.toml, as
# scripts/airframe_spec.py reads the description (it refuses an undescribed NAME).
description_value() {
  PYTHONPATH="$root/scripts" python3 -c 'import sys; from airframe_spec import description; print(description(sys.argv[1])[sys.argv[2]][sys.argv[3]])' "$1" "$2" "$3"
}

# aircraft_model NAME: prints the JSBSim model of aircraft/NAME.toml (its `[jsbsim] model`: the
# aircraft directory's MODEL/MODEL.xml).
aircraft_model() { description_value "$1" jsbsim model; }

# paper_test_flights NAME: the `paper` preset's test flights with seeds 11-18 of aircraft NAME,
# which no shipped estimator trained or fitted on (the analyses' independent flights, one directory
# per seed under out/turb/; expects the working directory `root`), in `flight_dirs`. A missing one is
# flown with the build's hil-sim (aircraft_target NAME first).
paper_test_flights() {
  flight_dirs=()
  local seed d
  mkdir -p out/turb
  for seed in 11 12 13 14 15 16 17 18; do
    d="out/turb/$1-$seed"
    [ -f "$d/manifest.json" ] || "$target/release/hil-sim" generate --aircraft "$1" --preset paper --test-only --seed "$seed" --out "$d" >&2
    flight_dirs+=("$d")
  done
}

# host_run RUN CSV [ARG...]: `hil-sim run --dataset CSV --firmware host ARG...` with the build's
# hil-sim (`bin`, analysis_binaries) into the directory RUN (estimates.csv, summary.json, log.txt),
# unless RUN holds a run newer than that hil-sim; written under RUN.tmp and moved into place whole, so
# an interrupted run leaves no RUN behind (the analyses' cache of stepped flights).
host_run() {
  local run="$1" csv="$2"
  shift 2
  [ "$run/summary.json" -nt "$bin/hil-sim" ] && return 0
  rm -rf "$run.tmp"
  mkdir -p "$run.tmp"
  "$bin/hil-sim" run --dataset "$csv" --firmware host "$@" --out "$run.tmp" > "$run.tmp/log.txt"
  rm -rf "$run"
  mv "$run.tmp" "$run"
}

# variant_names: the F-16's development variants (airframes/f16-variants/) by their specs' `name`,
# as scripts/fit-sigma names them, in `variants` (expects the working directory `root` and the
# project's .venv); refuses when none can be read.
variant_names() {
  local listed
  listed="$(PYTHONPATH="$root/scripts" .venv/bin/python -c 'from airframe_spec import named_variants; print("\n".join(n for n, _, _ in named_variants("f16")))')" ||
    { echo "${0#"$root"/}: cannot read airframes/f16-variants/ (scripts/airframe_spec.py)" >&2; exit 2; }
  [ -n "$listed" ] || { echo "${0#"$root"/}: airframes/f16-variants/ holds no variant spec" >&2; exit 2; }
  mapfile -t variants <<< "$listed"
}

# development_variants: variant_names, and their aircraft directories (out/sigma/aircraft/NAME)
# and seed-1 test flights (out/sigma/test/NAME) made by `scripts/fit-sigma --no-fit --out out/sigma`
# when one is missing (about a minute: it flies the seed-1 test flights and measures the committed
# 1σ on them).
development_variants() {
  local n
  variant_names
  for n in "${variants[@]}"; do
    if [ ! -f "out/sigma/test/$n/manifest.json" ] || [ ! -f "out/sigma/aircraft/$n/f16/f16.xml" ]; then
      echo "${0#"$root"/}: out/sigma lacks $n: making the variants' test flights with scripts/fit-sigma --no-fit --out out/sigma" >&2
      scripts/fit-sigma --no-fit --out out/sigma
      break
    fi
  done
}

# development_cards DIR SEED: the `paper` preset's test card with seed SEED flown on JSBSim's F-16
# (DIR/stock) and on each development variant (DIR/NAME, development_variants' aircraft
# directories) with the build's hil-sim (`bin`, analysis_binaries), each made once; their names,
# stock first, in `card_names`.
development_cards() {
  local n d air
  development_variants
  card_names=(stock "${variants[@]}")
  mkdir -p "$1"
  for n in "${card_names[@]}"; do
    d="$1/$n"
    [ -f "$d/manifest.json" ] && continue
    air=()
    [ "$n" = stock ] || air=(--aircraft-dir "out/sigma/aircraft/$n")
    "$bin/hil-sim" generate --preset paper --test-only --seed "$2" "${air[@]}" --out "$d" --force > /dev/null
  done
}
