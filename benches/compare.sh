#!/usr/bin/env bash
# Compares regolith binaries on the full-model benchmark (docs/BENCHMARKS.md): runs them
# alternately, REPS times each, and prints every run's particle-steps/s (millions) and the
# best per binary. The machine's speed drifts by 20% or more between minutes, so only
# interleaved runs of the binaries compared are worth comparing.
#
#   benches/compare.sh THREADS REPS BINARY...
#   e.g. cp target/release/regolith /tmp/before; (change, build); \
#        benches/compare.sh 2 6 /tmp/before target/release/regolith
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 THREADS REPS BINARY..." >&2
    exit 2
fi
threads=$1
reps=$2
shift 2
here="$(cd "$(dirname "$0")/.." && pwd)"
material='bodies.bed.material=MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.32, mu_2: 0.598, i_0: 0.278)'
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
declare -A runs best
for _ in $(seq "$reps"); do
    for bin in "$@"; do
        RAYON_NUM_THREADS=$threads "$bin" run "$here/scenes/bench_contact.ron" --set "$material" \
            --set time.end=3e-3 --out "$out" -q >/dev/null
        rate=$(sed -n 's/.*"particle_steps_per_s": *\([0-9.e+]*\).*/\1/p' "$out/summary.json")
        m=$(awk -v r="$rate" 'BEGIN { printf "%.2f", r / 1e6 }')
        runs[$bin]="${runs[$bin]:-} $m"
        if awk -v a="$m" -v b="${best[$bin]:-0}" 'BEGIN { exit !(a > b) }'; then
            best[$bin]=$m
        fi
    done
done
for bin in "$@"; do
    echo "$bin ($threads threads): best ${best[$bin]} M; runs${runs[$bin]}"
done
