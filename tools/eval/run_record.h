// One evaluated run (scene x method x budget x run index) and the tables written from them.
//   runs.csv        every run: timing, work done, error metrics, acceptance, stability flags
//   acceptance.csv  proposed/accepted mutations per path length per Markov chain run
//   kinds.csv       proposed/accepted mutations per mutation kind (the method's names: large, small,
//                   technique, bidir, lens, ...) per Markov chain run
//   refs.csv        per scene: where the reference came from and its own noise level
#pragma once
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "tools/eval/bands.h"
#include "tools/eval/metrics.h"

namespace mlt::eval {

struct RunRecord {
  std::string scene, method;     // method = the label (e.g. "pt", or "pt-biased" for a test method)
  std::string mode = "local";    // "local" (in-process) or "farm"
  int budgetIndex = 0;
  double budget = 0;             // seconds (equal time) or spp / mutations per pixel (equal samples)
  int run = 0;
  uint64_t seed = 0;
  double seconds = 0;            // real wall time of the run (bootstrap included)
  double planSeconds = -1;       // of which planning (the bootstrap); -1 = not measured (farm runs)
  double work = 0;               // spp (sample methods) or mutations per pixel (chains) requested
  uint64_t samples = 0;          // pixel samples or mutations actually done
  ImageMetrics metrics;
  bool markovChain = false;
  double acceptance = -1;        // overall; -1 for sample-based methods and when not reported (farm)
  std::vector<uint64_t> proposedPerLength, acceptedPerLength;
  std::vector<std::string> kinds;  // the method's mutation kinds, index of proposedPerKind
  std::vector<uint64_t> proposedPerKind, acceptedPerKind;
  int chains = 0, stuckChains = 0;  // chains with acceptance below the stuck threshold
  // Markov chains: the relMSE an ideal chain on the luminance target would reach with this run's mutations
  // (tools/eval/ideal_chain.h (I1), against the reference); relMSE / idealRelMSE is what the chain's
  // correlation costs when the chains render the whole image. -1 for sample methods and unknown counts.
  double idealRelMSE = -1;
  // The relMSE split by the reference's brightness (tools/eval/bands.h (B1); the bands add up to relMSE) and
  // the same split of idealRelMSE (-1 entries where idealRelMSE is -1). In bands.csv, not in runs.csv.
  BandValues bandRelMSE{};
  BandValues bandIdeal = kUnknownBands;
  int width = 0;                    // of the film, to name a pixel in a flag (not in runs.csv; 0 when unknown)
  std::vector<std::string> flags;   // filled by the stability analysis: "outlier", "stuck", "brightness"
};

struct ReferenceInfo {
  std::string scene;
  int width = 0, height = 0;     // the film size every run of the scene renders
  std::string source;            // "user:<path>" or "bdpt spp=... parts=... (cache key)"
  ReferenceNoise noise;
  double seconds = 0;            // time spent rendering it (0 when cached or user-supplied)
  bool cached = false;
};

void writeRunsCsv(std::ostream& os, const std::vector<RunRecord>& runs);
void writeAcceptanceCsv(std::ostream& os, const std::vector<RunRecord>& runs);
void writeKindsCsv(std::ostream& os, const std::vector<RunRecord>& runs);
void writeRefsCsv(std::ostream& os, const std::vector<ReferenceInfo>& refs);
// One row per run and band: scene,method,budget,run,band,rel_mse,ideal_rel_mse (empty where not known).
void writeBandsCsv(std::ostream& os, const std::vector<RunRecord>& runs);
// Reads what writeRunsCsv wrote (the per-length acceptance is not in runs.csv). Throws
// std::runtime_error naming the line on malformed input.
std::vector<RunRecord> readRunsCsv(std::istream& is);

// CSV field quoting (RFC 4180) and splitting, exposed for tests.
std::string csvQuote(const std::string& s);
std::vector<std::string> csvSplit(const std::string& line);

}  // namespace mlt::eval
