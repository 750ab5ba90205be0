#!/bin/bash
# Instructions per sample / mutation of every method, by difference of two callgrind runs (startup,
# scene load and bootstrap cancel): (I(n2) - I(n1)) / ((n2 - n1) * pixels).
#   bash tests/bench/instructions_per_sample.sh BINARY LABEL   (valgrind; ~12 min for the seven methods)
# SAMPLE_METHODS / CHAIN_METHODS (space-separated) pick the methods, e.g. SAMPLE_METHODS= CHAIN_METHODS=veach-mlt;
# SCENE_NAME another bundled scene (default cornell-box).
BIN=$1; LABEL=$2
SAMPLE_METHODS=${SAMPLE_METHODS-pt lt bdpt}
CHAIN_METHODS=${CHAIN_METHODS-pssmlt pssmlt-bdpt mmlt veach-mlt}
SCENE="$(cd "$(dirname "$0")/../.." && pwd)/scenes/${SCENE_NAME:-cornell-box}.xml"
W=128; H=128; PIX=$((W*H))
count() {  # args... -> total instructions
  valgrind --tool=callgrind --callgrind-out-file=/tmp/instr.$$.out "$BIN" render $SCENE --width $W --height $H \
    --threads 1 --in-process -q -o /tmp/instr.$$.exr "$@" > /dev/null 2>&1
  callgrind_annotate /tmp/instr.$$.out 2>/dev/null | grep -m1 "PROGRAM TOTALS" | awk '{gsub(",","",$1); print $1}'
}
for m in $SAMPLE_METHODS; do
  a=$(count --method $m --spp 1); b=$(count --method $m --spp 5)
  echo "$LABEL $m instructions/sample $(awk -v a=$a -v b=$b -v p=$PIX 'BEGIN{printf "%.1f", (b-a)/(4*p)}')"
done
for m in $CHAIN_METHODS; do
  a=$(count --method $m --mutations-per-pixel 2 --bootstrap 20000 --chains 64); b=$(count --method $m --mutations-per-pixel 10 --bootstrap 20000 --chains 64)
  echo "$LABEL $m instructions/mutation $(awk -v a=$a -v b=$b -v p=$PIX 'BEGIN{printf "%.1f", (b-a)/(8*p)}')"
done
rm -f /tmp/instr.$$.out /tmp/instr.$$.exr
