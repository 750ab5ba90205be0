#!/usr/bin/env bash
# The farm's own cost on the README's default job (what tools/run-default.sh renders):
#   mltfarm render scenes/cornell-box.xml --method mmlt --mutations-per-pixel 256
# through the local farm (the default: a coordinator + one worker process per core on loopback) and
# --in-process, alternately, RUNS times each. Prints wall, user and system time of every run (the whole
# process tree: the coordinator and the workers are children of mltfarm), the best and the median of
# each side, and their ratios; checks that every farm image has the in-process image's pixels, bit for
# bit (tests/bench/exr_pixels), and exits 1 if not. A printed figure, not a timed test: the machine may
# be shared, so the load average is printed before and after.
#
#   bash tests/bench/farm_overhead.sh [RUNS=5] [TOOLS_DIR=build/tools] [EXR_PIXELS=build/tests/exr_pixels]
#   extra arguments for both renders: MLTFARM_BENCH_ARGS="--seed 3" bash tests/bench/farm_overhead.sh
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
RUNS="${1:-5}"
TOOLS="${2:-$ROOT/build/tools}"
EXR_PIXELS="${3:-$ROOT/build/tests/exr_pixels}"
for f in "$TOOLS/mltfarm" "$TOOLS/mltfarm-coordinator" "$TOOLS/mltfarm-worker" "$EXR_PIXELS"; do
  [[ -x "$f" ]] || { echo "farm_overhead: $f is missing (build the targets mltfarm mltfarm-coordinator mltfarm-worker exr_pixels)" >&2; exit 2; }
done
TMP="$(mktemp -d /tmp/mltfarm-overhead-XXXXXX)"
trap 'rm -rf "$TMP"' EXIT
# shellcheck disable=SC2206
EXTRA=(${MLTFARM_BENCH_ARGS:-})
JOB=(render "$ROOT/scenes/cornell-box.xml" --method mmlt --mutations-per-pixel 256 -q "${EXTRA[@]}")

echo "job: mltfarm ${JOB[*]} [--in-process]"
echo "machine: $(nproc) cores, $(uptime | sed 's/.*load average/load average/')"
printf '%-4s %-11s %8s %8s %8s\n' run mode wall user sys
identical=1
run() {  # run MODE OUT [ARGS...] -> appends "wall user sys" to $TMP/MODE.times
  local mode="$1" out="$2"
  shift 2
  /usr/bin/time -f '%e %U %S' -o "$TMP/time" "$TOOLS/mltfarm" "${JOB[@]}" -o "$out" "$@" > /dev/null
  cat "$TMP/time" >> "$TMP/$mode.times"
  read -r wall user sys < "$TMP/time"
  printf '%-4s %-11s %8.2f %8.2f %8.2f\n' "$i" "$mode" "$wall" "$user" "$sys"
}
for i in $(seq 1 "$RUNS"); do
  run in-process "$TMP/in.exr" --in-process
  run farm "$TMP/farm.exr"
  if ! "$EXR_PIXELS" "$TMP/in.exr" "$TMP/farm.exr" > "$TMP/cmp"; then
    identical=0
    cat "$TMP/cmp"
  fi
done

# min and median of column $2 (1 wall, 2 user, 3 sys) of file $1
stat() { awk -v c="$2" '{print $c}' "$1" | sort -g | awk '{v[NR]=$1} END {printf "%.3f %.3f", v[1], (NR%2 ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2)}'; }
echo
printf '%-11s %15s %15s %15s\n' "" "wall best/med" "user best/med" "sys best/med"
for mode in in-process farm; do
  printf '%-11s' "$mode"
  for c in 1 2 3; do read -r lo med <<< "$(stat "$TMP/$mode.times" "$c")"; printf ' %7.2f/%-7.2f' "$lo" "$med"; done
  echo
done
ratio() { read -r a am <<< "$(stat "$TMP/in-process.times" "$1")"; read -r b bm <<< "$(stat "$TMP/farm.times" "$1")"
          awk -v a="$a" -v b="$b" -v am="$am" -v bm="$bm" 'BEGIN {printf "%.3f (best) %.3f (median)", b / a, bm / am}'; }
echo "farm / in-process wall: $(ratio 1)"
# Each farm run against the in-process run just before it: a machine whose speed drifts over minutes
# (a shared host) moves both sides of a pair alike, so the median of these ratios is the steadier figure.
pairs=$(paste -d' ' "$TMP/in-process.times" "$TMP/farm.times" | awk '{print $4 / $1}' | sort -g)
echo "farm / in-process wall, run by run: $(echo $pairs | tr ' ' '\n' | awk '{printf "%.3f ", $1}')(median $(echo "$pairs" | awk '{v[NR]=$1} END {printf "%.3f", (NR%2 ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2)}'))"
# A distribution-free 95% interval for the median pair ratio: order statistics k and n + 1 - k, with k the
# largest such that P(Binomial(n, 1/2) < k) <= 0.025 (the sign test). Needs n >= 6.
echo "$pairs" | awk '{v[NR]=$1} END {n=NR; if (n < 6) exit; p=0.5^n; c=0; k=0
  for (i=0; i<n; i++) { c+=p; if (c > 0.025) break; k=i+1; p=p*(n-i)/(i+1) }
  if (k >= 1) printf "median pair ratio, 95%% interval (sign test, order statistics %d and %d of %d): %.3f to %.3f\n", k, n+1-k, n, v[k], v[n+1-k]}'
cpu() { awk '{s = $2 + $3; print s}' "$1" | sort -g | head -1; }
echo "farm / in-process CPU (user+sys, best): $(awk -v a="$(cpu "$TMP/in-process.times")" -v b="$(cpu "$TMP/farm.times")" 'BEGIN {printf "%.3f (%.2f s vs %.2f s)", b / a, b, a}')"
echo "machine after: $(uptime | sed 's/.*load average/load average/')"
if [[ $identical == 1 ]]; then
  echo "pixels: identical in all $RUNS runs ($(awk '{print $4, $5}' "$TMP/cmp" | head -1))"
else
  echo "pixels: DIFFER between the farm and --in-process" >&2
  exit 1
fi
