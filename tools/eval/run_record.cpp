#include "tools/eval/run_record.h"

#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

namespace mlt::eval {

std::string csvQuote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::vector<std::string> csvSplit(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return fields;
}

static const char* kRunsHeader =
    "scene,method,mode,budget_index,budget,run,seed,seconds,work,samples,relMSE,MSE,MAE,meanErr,"
    "acceptance,chains,stuck_chains,non_finite,flags,plan_seconds,top_share,pixels,ideal_relMSE";
// The header before ideal_relMSE (read as -1: not known).
static const char* kRunsHeader22 =
    "scene,method,mode,budget_index,budget,run,seed,seconds,work,samples,relMSE,MSE,MAE,meanErr,"
    "acceptance,chains,stuck_chains,non_finite,flags,plan_seconds,top_share,pixels";
// The header before top_share and pixels (runs.csv files written before them are still read; both read as 0).
static const char* kRunsHeader20 =
    "scene,method,mode,budget_index,budget,run,seed,seconds,work,samples,relMSE,MSE,MAE,meanErr,"
    "acceptance,chains,stuck_chains,non_finite,flags,plan_seconds";

static std::string joinFlags(const std::vector<std::string>& flags) {
  std::string s;
  for (const auto& f : flags) s += (s.empty() ? "" : ";") + f;
  return s;
}

void writeRunsCsv(std::ostream& os, const std::vector<RunRecord>& runs) {
  os << kRunsHeader << "\n";
  for (const RunRecord& r : runs) {
    const ImageMetrics& m = r.metrics;
    os << fmt::format("{},{},{},{},{},{},{},{:.6f},{},{},{:.9g},{:.9g},{:.9g},{:.9g},{},{},{},{},{},{},{:.6g},{},{}\n",
                      csvQuote(r.scene), csvQuote(r.method), r.mode, r.budgetIndex, r.budget, r.run, r.seed,
                      r.seconds, r.work, r.samples, m.relMSE, m.mse, m.mae, m.meanErr,
                      r.markovChain && r.acceptance >= 0 ? fmt::format("{:.6g}", r.acceptance) : std::string(), r.chains,
                      r.stuckChains, m.nonFinite, csvQuote(joinFlags(r.flags)),
                      r.planSeconds >= 0 ? fmt::format("{:.6f}", r.planSeconds) : std::string(), m.topShare, m.pixels,
                      r.idealRelMSE >= 0 ? fmt::format("{:.6g}", r.idealRelMSE) : std::string());
  }
}

void writeAcceptanceCsv(std::ostream& os, const std::vector<RunRecord>& runs) {
  os << "scene,method,mode,budget_index,budget,run,path_length,proposed,accepted\n";
  for (const RunRecord& r : runs) {
    if (!r.markovChain) continue;
    for (size_t k = 0; k < r.proposedPerLength.size(); ++k) {
      uint64_t acc = k < r.acceptedPerLength.size() ? r.acceptedPerLength[k] : 0;
      if (r.proposedPerLength[k] == 0) continue;
      os << fmt::format("{},{},{},{},{},{},{},{},{}\n", csvQuote(r.scene), csvQuote(r.method), r.mode,
                        r.budgetIndex, r.budget, r.run, k, r.proposedPerLength[k], acc);
    }
  }
}

void writeKindsCsv(std::ostream& os, const std::vector<RunRecord>& runs) {
  os << "scene,method,mode,budget_index,budget,run,kind,proposed,accepted\n";
  for (const RunRecord& r : runs) {
    if (!r.markovChain) continue;
    for (size_t k = 0; k < r.proposedPerKind.size() && k < r.kinds.size(); ++k) {
      const uint64_t acc = k < r.acceptedPerKind.size() ? r.acceptedPerKind[k] : 0;
      os << fmt::format("{},{},{},{},{},{},{},{},{}\n", csvQuote(r.scene), csvQuote(r.method), r.mode,
                        r.budgetIndex, r.budget, r.run, csvQuote(r.kinds[k]), r.proposedPerKind[k], acc);
    }
  }
}

void writeRefsCsv(std::ostream& os, const std::vector<ReferenceInfo>& refs) {
  os << "scene,source,parts,relMSE_floor,MSE_floor,mean_rel_stderr,seconds,cached\n";
  for (const ReferenceInfo& r : refs)
    os << fmt::format("{},{},{},{:.9g},{:.9g},{:.9g},{:.3f},{}\n", csvQuote(r.scene), csvQuote(r.source),
                      r.noise.parts, r.noise.relMSEFloor, r.noise.mseFloor, r.noise.meanRelStdErr, r.seconds,
                      r.cached ? 1 : 0);
}

void writeBandsCsv(std::ostream& os, const std::vector<RunRecord>& runs) {
  os << "scene,method,budget,run,band,rel_mse,ideal_rel_mse\n";
  for (const RunRecord& r : runs)
    for (int b = 0; b < kBands; ++b) {
      const double ideal = r.bandIdeal[size_t(b)];
      os << fmt::format("{},{},{:g},{},{},{:.9g},{}\n", csvQuote(r.scene), csvQuote(r.method), r.budget, r.run,
                        csvQuote(bandName(b)), r.bandRelMSE[size_t(b)], ideal >= 0 ? fmt::format("{:.9g}", ideal) : "");
    }
}

std::vector<RunRecord> readRunsCsv(std::istream& is) {
  std::string line;
  if (!std::getline(is, line) || (line != kRunsHeader && line != kRunsHeader22 && line != kRunsHeader20))
    throw std::runtime_error("runs.csv line 1: unexpected header (expected '" + std::string(kRunsHeader) + "')");
  const size_t fields = line == kRunsHeader ? 23 : line == kRunsHeader22 ? 22 : 20;
  std::vector<RunRecord> runs;
  int lineNo = 1;
  while (std::getline(is, line)) {
    ++lineNo;
    if (line.empty()) continue;
    auto f = csvSplit(line);
    if (f.size() != fields)
      throw std::runtime_error(fmt::format("runs.csv line {}: expected {} fields, got {}", lineNo, fields, f.size()));
    try {
      RunRecord r;
      r.scene = f[0];
      r.method = f[1];
      r.mode = f[2];
      r.budgetIndex = std::stoi(f[3]);
      r.budget = std::stod(f[4]);
      r.run = std::stoi(f[5]);
      r.seed = std::stoull(f[6]);
      r.seconds = std::stod(f[7]);
      r.work = std::stod(f[8]);
      r.samples = std::stoull(f[9]);
      r.metrics.relMSE = std::stod(f[10]);
      r.metrics.mse = std::stod(f[11]);
      r.metrics.mae = std::stod(f[12]);
      r.metrics.meanErr = std::stod(f[13]);
      r.acceptance = f[14].empty() ? -1 : std::stod(f[14]);
      r.chains = std::stoi(f[15]);
      r.markovChain = !f[14].empty() || r.chains > 0;
      r.stuckChains = std::stoi(f[16]);
      r.metrics.nonFinite = std::stoull(f[17]);
      std::stringstream flags(f[18]);
      for (std::string flag; std::getline(flags, flag, ';');)
        if (!flag.empty()) r.flags.push_back(flag);
      r.planSeconds = f[19].empty() ? -1 : std::stod(f[19]);
      if (fields > 20) {
        r.metrics.topShare = std::stod(f[20]);
        r.metrics.pixels = std::stoull(f[21]);
      }
      if (fields > 22) r.idealRelMSE = f[22].empty() ? -1 : std::stod(f[22]);
      runs.push_back(std::move(r));
    } catch (const std::logic_error& e) {
      throw std::runtime_error(fmt::format("runs.csv line {}: bad number ({})", lineNo, e.what()));
    }
  }
  return runs;
}

}  // namespace mlt::eval
