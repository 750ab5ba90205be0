// summary.md: the markdown report of an evaluation. Per scene: the reference and its noise floor, the
// charts (with the machine and the budgets stated next to each), the methods ranked by relMSE at equal
// time (every budget), the stability verdicts (which methods fail and how) and the error maps.
// File names shared with tools/eval/charts.py:
//   error_time_<scene>.png, spread_<scene>.png, acceptance_<scene>.png, maps/<scene>_<method>_error.png
#pragma once
#include <iosfwd>
#include <string>

namespace mlt::eval {

struct EvalConfig;
struct EvalResult;

// "AMD EPYC (2 cores)" from /proc/cpuinfo and the hardware concurrency.
std::string machineDescription();
void writeSummary(std::ostream& os, const EvalConfig& config, const EvalResult& result);

}  // namespace mlt::eval
