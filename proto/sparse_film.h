// A film's raw sums with the zeros left out, for the upload of a partial film. Most of a task's film is
// zero words: Markov chain methods never touch the pixel sums and counts, an mmlt task holds one or two
// path lengths of a chain-length-sorted plan (the other length layers stay zero), and a small task
// leaves dark or unreached pixels at zero. The stream is the dense layout of encodeFilm (proto/convert.h)
// as 8-byte words, written as runs: varint(zero words), varint(literal words), the literal words. Exact
// (decode(encode(f)) has the same bits), one pass each way, never larger than the dense bytes + 20.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/film/film.h"

namespace mlt::wire {

std::string encodeFilmZeroRuns(const Film& film);
// Throws WireError when the stream does not decode to exactly the film of width x height with these
// splat layers.
Film decodeFilmZeroRuns(int width, int height, const std::string& bytes, uint64_t nonFinite,
                        const std::vector<uint32_t>& layers);
// The largest encoded size of a film of this size (the receiver's bound on the announced size).
size_t maxZeroRunsBytes(int width, int height, size_t splatLayers);

}  // namespace mlt::wire
