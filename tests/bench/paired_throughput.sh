#!/bin/bash
# Two mltfarm binaries' throughput, measured side by side (docs/PERFORMANCE.md, issue 9's figures).
#   bash tests/bench/paired_throughput.sh BASE NEW ROUNDS [render options...]
# Each round runs BASE on CPU 0 and NEW on CPU 1 at the same time (one thread each, the Cornell box at
# 256x256 in-process), then the same with the CPUs swapped, so that a host whose cores or speed differ
# from minute to minute weighs on both alike. Prints every pair's printed samples or mutations per second
# and the geometric mean of NEW / BASE. Default options: --method mmlt --mutations-per-pixel 48
# --direct-light chains.
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 BASE NEW ROUNDS [render options...]" >&2; exit 2; }
base=$1 new=$2 rounds=$3
shift 3
opts=("$@")
[ ${#opts[@]} -gt 0 ] || opts=(--method mmlt --mutations-per-pixel 48 --direct-light chains)
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# The chains' summary ("= R mutations/s") or a sample job's ("(R samples/s)").
rate() { sed -n 's/.*= \([0-9.e+]*\) \(mutations\|samples\)\/s$/\1/p; s/.*(\([0-9.e+]*\) samples\/s).*/\1/p' "$1" | tail -1; }
ratios=()
for i in $(seq 1 "$rounds"); do
  for swap in 0 1; do
    taskset -c $swap "$base" render "$root/scenes/cornell-box.xml" "${opts[@]}" --width 256 --height 256 \
      --threads 1 --in-process -o "$out/base.exr" > "$out/base.log" 2>&1 &
    taskset -c $((1 - swap)) "$new" render "$root/scenes/cornell-box.xml" "${opts[@]}" --width 256 --height 256 \
      --threads 1 --in-process -o "$out/new.exr" > "$out/new.log" 2>&1 &
    wait
    b=$(rate "$out/base.log") n=$(rate "$out/new.log")
    r=$(python3 -c "print(f'{$n / $b:.4f}')")
    ratios+=("$r")
    echo "round $i, base on CPU $swap: base $b, new $n, new/base $r"
  done
done
python3 -c "import math, sys; r = [float(x) for x in sys.argv[1:]]; print(f'geometric mean new/base {math.exp(sum(map(math.log, r)) / len(r)):.4f} (min {min(r):.3f}, max {max(r):.3f}, {len(r)} runs each)')" "${ratios[@]}"
