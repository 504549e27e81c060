#!/usr/bin/env bash
# Extraction accuracy against ground truth, as quoted in the README: five synthetic sets of 24
# photos (2400×1600, seed 101; clean billiard balls with and without a plate, clean balls of the
# three materials, realistic, hard), 36 clean mixed-spin shots with a plate (seed 8) and 24 clean
# grazing shots (psi 72–86°, seed 77) with and without a plate, extracted with the default
# settings, compared with truth.csv and with psi's Cramér–Rao bound (`bench psi-bound`).
# Usage: docs/accuracy.sh [WORKDIR]   (needs a release build: cargo build --release)
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${CARGO_TARGET_DIR:-target}/release/streakfit"
work="${1:-$(mktemp -d)}"
# A set's photos, and psi's Cramér–Rao bound for the same planned shots (psi_bound.csv).
make_set() {
  "$bin" synth "$@" >/dev/null
  "$bin" bench psi-bound "$@" >/dev/null
}
make_set --out "$work/clean_plate" --tier clean --shots 24 --seed 101 --background
make_set --out "$work/clean" --tier clean --shots 24 --seed 101
make_set --out "$work/clean_materials" --tier clean --shots 24 --seed 101 --material mixed
make_set --out "$work/realistic" --tier realistic --shots 24 --seed 101
make_set --out "$work/hard" --tier hard --shots 24 --seed 101
make_set --out "$work/mixed" --tier clean --shots 36 --seed 8 --spin-modes mixed --background
make_set --out "$work/grazing_plate" --tier clean --shots 24 --seed 77 --psi 72:86 --background
make_set --out "$work/grazing" --tier clean --shots 24 --seed 77 --psi 72:86
args=()
for set in clean_plate clean clean_materials realistic hard mixed grazing_plate grazing; do
  n=$(find "$work/$set" -name 'shot_*' | wc -l)
  start=$(date +%s.%N)
  "$bin" extract "$work/$set" --out "$work/$set.csv" --jobs 2 || true   # exit 1 when a row is `error`
  end=$(date +%s.%N)
  echo "$set: $(echo "$n / ($end - $start)" | bc -l | cut -c1-4) images/s on 2 cores (decode included)"
  args+=("$work/$set" "$work/$set.csv")
done
python3 docs/compare_truth.py "${args[@]}"
