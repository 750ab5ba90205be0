// A vertex's BSDF numbers from its block of the sample vector (sampler/sample_source.h: kBsdfDims numbers
// per bounce: [0] uComponent, [1,2] uDir, [3] Russian roulette), reading only those the BSDF's sample()
// reads (Bsdf::reads). The others keep their place in the block and are never read, so a Markov chain
// over primary samples spends nothing on them: on a diffuse surface the lobe choice, on a mirror all
// three. The source is left at [3], the roulette number.
#pragma once
#include "common/core/vec.h"
#include "common/interfaces/bsdf.h"
#include "common/sampler/sample_source.h"

namespace mlt {

struct BsdfNumbers {
  float uComponent = 0;  // 0 where the BSDF does not read it
  Vec2 uDir;             // (0, 0) where the BSDF does not read it
};

inline BsdfNumbers readBsdfNumbers(SampleSource& source, int blockStart, BsdfReads reads) {
  BsdfNumbers n;
  if (reads.component) {
    source.seek(blockStart);
    n.uComponent = source.next1D();
  }
  if (reads.direction) {
    source.seek(blockStart + 1);
    n.uDir = source.next2D();
  }
  source.seek(blockStart + 3);
  return n;
}

}  // namespace mlt
