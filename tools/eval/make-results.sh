#!/usr/bin/env bash
# Regenerates the results page: docs/RESULTS.md and docs/results/* (charts, runs.csv, ...), at the size
# people render (issue 9 item 6).
#
#   tools/eval/make-results.sh        # every step below, one after the other: ~2.5 hours on one core
#
# Per scene: every method at the short budgets (4 and 16 s), RUNS runs each with its own job seed; on
# LONG_SCENES also LONG_METHODS at 64 s. Each call of `mltfarm eval` writes to $WORK/<scene>-<phase>;
# tools/eval/results_page.py pools them into docs/results and writes docs/RESULTS.md. Settings come from
# the environment:
#   SCENES=cornell-box,caustic-mirror,door-ajar,glossy-plates   METHODS=pt,bdpt,pssmlt,pssmlt-bdpt,mmlt,rjmlt,veach-mlt
#   BUDGETS=4,16  LONG_SCENES=cornell-box,caustic-mirror  LONG_METHODS=pt,bdpt,mmlt,pssmlt  LONG_BUDGETS=64
#   (LONG_SCENES= , set and empty, runs no scene at the long budgets)
#   RUNS=5  RES=256  THREADS=1  REF_SPP=2048  CPU= (a core to pin every run to with taskset; empty = none)
#   CPUS=a,b (instead of CPU: every method on both cores, two passes with the cores swapped, so that each
#     point has 2 x RUNS runs, RUNS seeds on each core; the page of 2026-12-05 has every scene but
#     caustic-mirror and the Cornell box's 64-s group so)
#   REF_SPPS=scene=spp,... (a scene's own reference size instead of REF_SPP; the page of 2026-12-05:
#     REF_SPPS=caustic-mirror=25600,cornell-box=4096,door-ajar=3072,glossy-plates=2048,textured-serialized=2048
#     and REF_SPP=1024, so that each reference's noise floor is at most a tenth of the best method's
#     error, where it is met)
#   REF_METHODS=scene=method,... (a scene's reference method instead of REF_METHOD=bdpt; the page of
#     2026-12-05 from session 40 on: REF_METHODS=caustic-mirror=pt with REF_SPPS' caustic-mirror=25600:
#     on that scene pt's error per second is half bdpt's, see docs/RESULTS.md)
#   WORK=build/results-work  BUILD=build  PAGE_ONLY=1 (only pool what $WORK holds and write the page)
#   NOTE="..." (a sentence added to the page header, e.g. which commits the runs came from)
#   KEEP=1 (the page keeps the current docs/results tables' rows of every (scene, method, budget) this run
#     does not redo: a page with a few scenes rerun, or a budget added to one, and the rest as it was;
#     results_page.py --keep)
#   HEADER=FILE (a Markdown file for the page's header instead of the generated one, e.g. one that says
#     where each scene's rows come from when KEEP pools several sessions' runs)
# The references (REF_METHOD, REF_SPP spp in 4 independent parts, THREADS threads; 2 with CPUS) are cached in $WORK/refs, keyed by
# the scene's content hash and the settings, so a second regeneration skips them. Two instances with
# disjoint SCENES (and CPU=0 / CPU=1) can run side by side; run one more with PAGE_ONLY=1 at the end.
set -euo pipefail
cd "$(dirname "$0")/../.."
SCENES=${SCENES:-cornell-box,caustic-mirror,door-ajar,glossy-plates}
METHODS=${METHODS:-pt,bdpt,pssmlt,pssmlt-bdpt,mmlt,rjmlt,veach-mlt}
BUDGETS=${BUDGETS:-4,16}
LONG_SCENES=${LONG_SCENES-cornell-box,caustic-mirror}  # set but empty: no long phase
LONG_METHODS=${LONG_METHODS:-pt,bdpt,mmlt,pssmlt}
LONG_BUDGETS=${LONG_BUDGETS:-64}
RUNS=${RUNS:-5}
RES=${RES:-256}
THREADS=${THREADS:-1}
REF_SPP=${REF_SPP:-2048}
REF_SPPS=${REF_SPPS:-}
REF_METHOD=${REF_METHOD:-bdpt}
REF_METHODS=${REF_METHODS:-}
scene_entry() {  # scene list default -> the scene's entry of a scene=value list, else default
  local entry
  for entry in ${2//,/ }; do
    if [[ "${entry%%=*}" == "$1" ]]; then echo "${entry#*=}"; return; fi
  done
  echo "$3"
}
ref_spp() { scene_entry "$1" "$REF_SPPS" "$REF_SPP"; }             # scene -> its reference size
ref_method() { scene_entry "$1" "$REF_METHODS" "$REF_METHOD"; }    # scene -> its reference method
ref_opts() { echo "--ref-spp $(ref_spp "$1") --ref-method $(ref_method "$1")"; }  # scene -> mltfarm eval's reference options
BUILD=${BUILD:-build}
WORK=${WORK:-$BUILD/results-work}
PIN=()
PINNED=${CPU:-${CPUS:-}}  # runs pinned (CPU or CPUS): the page header says so
if [[ -n "${CPU:-}" ]]; then PIN=(taskset -c "$CPU"); fi

if [[ "${PAGE_ONLY:-0}" != "1" ]]; then
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD" --target mltfarm -j"$(nproc)"
  mkdir -p "$WORK/refs"
  scene_file() {  # scene -> its file under scenes/
    local f
    for f in scenes/"$1".xml scenes/"$1".pbrt; do [[ -f "$f" ]] && echo "$f" && return; done
    echo "make-results.sh: no scenes/$1.xml or scenes/$1.pbrt" >&2
    exit 2
  }
  run_eval() {  # scene phase methods budgets [cpu]: into $WORK/<scene>-<phase>
    local out="$WORK/$1-$2" file pin=("${PIN[@]}")
    file=$(scene_file "$1")
    [[ -n "${5:-}" ]] && pin=(taskset -c "$5")
    rm -rf "$out"
    mkdir -p "$out"
    ln -s "$(realpath "$WORK/refs")" "$out/refs"
    echo "== $1 $2: $3 at $4 s${5:+ on CPU $5} ($(date -u +%H:%M:%S))"
    "${pin[@]}" "$BUILD/tools/mltfarm" eval --scenes "$file" --methods "$3" --runs "$RUNS" \
      --budgets "$4" --width "$RES" --height "$RES" --threads "$THREADS" $(ref_opts "$1") \
      --no-maps --no-charts -q --out "$out"
  }
  # CPUS=a,b: the scene's methods in two halves, each half on each core in turn (two passes, the cores
  # swapped), so that every method's runs come from both cores: this host's cores ran up to ~25% apart
  # within an hour (docs/RESULTS.md, glossy-plates), enough to move one method's equal-time rows against
  # another's. The reference is built first, on both cores, so that the two halves do not both build it.
  run_phase() {  # scene phase methods budgets
    if [[ -z "${CPUS:-}" ]]; then run_eval "$@"; return; fi
    local a=${CPUS%%,*} b=${CPUS#*,} m half1="" half2="" i=0
    for m in ${3//,/ }; do
      if (( i % 2 == 0 )); then half1+="${half1:+,}$m"; else half2+="${half2:+,}$m"; fi
      i=$((i + 1))
    done
    local refdir="$WORK/$1-refbuild"
    rm -rf "$refdir"; mkdir -p "$refdir"; ln -s "$(realpath "$WORK/refs")" "$refdir/refs"
    "$BUILD/tools/mltfarm" eval --scenes "$(scene_file "$1")" --methods pt --runs 1 --budgets 1 --width "$RES" \
      --height "$RES" --threads 2 $(ref_opts "$1") --no-maps \
      --no-charts -q --out "$refdir" > /dev/null
    local pass first second pids
    for pass in 1 2; do
      if (( pass == 1 )); then first=$a second=$b; else first=$b second=$a; fi
      pids=()
      run_eval "$1" "$2-${pass}a" "$half1" "$4" "$first" & pids+=($!)
      if [[ -n "$half2" ]]; then run_eval "$1" "$2-${pass}b" "$half2" "$4" "$second" & pids+=($!); fi
      for pid in "${pids[@]}"; do wait "$pid"; done  # a failed half stops the script (set -e)
    done
  }
  for scene in ${SCENES//,/ }; do
    run_phase "$scene" short "$METHODS" "$BUDGETS"
    if [[ ",$LONG_SCENES," == *",$scene,"* ]]; then run_phase "$scene" long "$LONG_METHODS" "$LONG_BUDGETS"; fi
  done
fi

{
  echo "# Results: accuracy against speed at ${RES}x${RES}"
  echo
  echo "Generated by \`tools/eval/make-results.sh\` on $(date -u +%Y-%m-%d), commit \`$(git rev-parse --short HEAD)\`"
  echo "(settings and the exact \`mltfarm eval\` calls: the script's header). Film ${RES}x${RES}; ${THREADS} thread(s) per run"
  echo "${PINNED:+pinned to one core }(equal time: each run's work is calibrated so that the whole job, bootstrap"
  echo "included, fits the budget; the charts plot the real wall time); ${RUNS} runs with different job seeds"
  echo "per point${CPUS:+, each seed run on both cores (CPUs ${CPUS}: 2 x ${RUNS} runs)}; every method at ${BUDGETS} s, the leading methods of some scenes also at ${LONG_BUDGETS} s (each"
  echo "scene's table shows which)."${NOTE:+ $NOTE}
  echo "References: ${REF_METHOD}${REF_METHODS:+ (per scene: ${REF_METHODS})} in 4 independent parts (their spread gives the reference's own noise floor and"
  echo "brightness error, reported per scene). relMSE = mean over pixels and channels of"
  echo "(x - r)^2 / (r^2 + 0.01); brightness = relative error of the image mean. Raw data:"
  echo "[runs.csv](results/runs.csv), [acceptance.csv](results/acceptance.csv), [refs.csv](results/refs.csv), [bands.csv](results/bands.csv)."
  echo "Flags (outlier, stuck chain, brightness) come from \`tools/eval/stability.h\`."
} > "$WORK/header.md"
if [[ -n "${HEADER:-}" ]]; then cp "$HEADER" "$WORK/header.md"; fi
mkdir -p docs/results
keep=()
if [[ "${KEEP:-0}" == "1" ]]; then  # the current page's tables, before they are replaced
  rm -rf "$WORK/kept-page"
  mkdir -p "$WORK/kept-page"
  cp docs/results/*.csv "$WORK/kept-page/"
  keep=(--keep "$WORK/kept-page")
fi
rm -rf docs/results/*.png docs/results/*.csv docs/results/maps docs/results/summary.md
/usr/bin/python3 tools/eval/results_page.py --out docs/results --page docs/RESULTS.md --header "$WORK/header.md" \
  "${keep[@]}" \
  $(ls -d "$WORK"/*-short "$WORK"/*-short-?? "$WORK"/*-long "$WORK"/*-long-?? 2>/dev/null)
