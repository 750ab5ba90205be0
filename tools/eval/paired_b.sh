#!/usr/bin/env bash
# OLD=... [NEW=...] tools/eval/paired_b.sh SCENE METHOD SEEDS [extra args]: b of the old and the new combination, same seeds
scene=$1; method=$2; seeds=$3; shift 3
for seed in $(seq 1 $seeds); do
  o=$(${OLD:?set OLD to the binary before} render scenes/$scene --method $method --in-process --seed $seed -o /tmp/p_old.exr "$@" 2>&1 | grep '^b = ' | awk '{print $3}')
  n=$(${NEW:-build/tools/mltfarm} render scenes/$scene --method $method --in-process --seed $seed -o /tmp/p_new.exr "$@" 2>&1 | grep '^b = ' | awk '{print $3, $5}')
  echo "$scene $method $seed $o $n"
done
