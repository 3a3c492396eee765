// The catalogue of selection methods: --scheduler NAME resolves here, and
// nowhere else (a new method adds one entry).
#include <functional>
#include <sstream>

#include "thinlod/backbone/scheduler.h"
#include "thinlod/backbone/time_critical_scheduler.h"

namespace thinlod::backbone {
namespace {

using Factory = std::function<Result<std::unique_ptr<Scheduler>>(const SchedulerOptions&)>;

struct CatalogueEntry {
  SchedulerEntry entry;
  Factory make;
};

const std::vector<CatalogueEntry>& entries() {
  static const std::vector<CatalogueEntry> kEntries = {
      {{"accuracy-curve", "curves",
        "Pasman-Jansen: accuracy curves up the tree, one uniform target under the budgets", false},
       [](const SchedulerOptions& o) { return makeAccuracyCurveScheduler(o.config); }},
      {{"vrml-static", "static",
        "VRML97 static LOD: LOD ranges and distance bands at the current position, no budgets",
        false},
       [](const SchedulerOptions& o) { return makeVrmlStaticScheduler(o.config, o.vrml); }},
      {{"greedy-fs93", "greedy",
        "Funkhouser-Sequin 1993: greedy benefit per triangle under the polygon budget", false},
       [](const SchedulerOptions& o) { return makeGreedyScheduler(o.config, o.greedy); }},
      {{"aslod", "",
        "Schmalstieg-Fuhrmann ASLOD: triangles allocated analytically by projected area", false},
       [](const SchedulerOptions& o) { return makeAslodScheduler(o.config, o.aslod); }},
      {{"span-of-level-changed", "slc",
        "Yu-Liang-Chen: importance heap on the span of level changed under the polygon budget",
        false},
       [](const SchedulerOptions& o) {
         return makeSpanOfLevelChangedScheduler(o.config, o.spanOfLevelChanged);
       }},
      {{"active-set", "time-critical",
        "Gobbetti-Bouvier 1999: per-object resolutions by an any-time active-set optimiser "
        "under the polygon or the frame-time budget",
        false},
       [](const SchedulerOptions& o) {
         return makeTimeCriticalScheduler(o.config, o.timeCritical);
       }},
      {{"brute-force", "", "every combination of options (exponential; tests and benchmarks only)",
        true},
       [](const SchedulerOptions& o) { return makeBruteForceScheduler(o.config, o.bruteForce); }},
  };
  return kEntries;
}

const CatalogueEntry* find(const std::string& nameOrAlias) {
  for (const CatalogueEntry& e : entries())
    if (nameOrAlias == e.entry.name || (*e.entry.alias && nameOrAlias == e.entry.alias)) return &e;
  return nullptr;
}

}  // namespace

const std::vector<SchedulerEntry>& schedulerCatalogue() {
  static const std::vector<SchedulerEntry> kCatalogue = [] {
    std::vector<SchedulerEntry> out;
    for (const CatalogueEntry& e : entries()) out.push_back(e.entry);
    return out;
  }();
  return kCatalogue;
}

Result<const char*> canonicalSchedulerName(const std::string& nameOrAlias) {
  if (const CatalogueEntry* e = find(nameOrAlias)) return e->entry.name;
  std::string known;
  for (const CatalogueEntry& e : entries()) {
    if (!known.empty()) known += ", ";
    known += e.entry.name;
  }
  return Status(ErrorCode::kNotFound,
                "unknown scheduler '" + nameOrAlias + "' (known: " + known + ")");
}

Result<std::unique_ptr<Scheduler>> makeScheduler(const std::string& nameOrAlias,
                                                 const SchedulerOptions& options) {
  const Result<const char*> name = canonicalSchedulerName(nameOrAlias);
  if (!name.ok()) return name.status();
  return find(*name)->make(options);
}

std::string schedulerHelp() {
  std::ostringstream out;
  for (const CatalogueEntry& e : entries()) {
    if (e.entry.forExperiments) continue;
    if (out.tellp() > 0) out << "\n";
    out << e.entry.name;
    if (*e.entry.alias) out << " (" << e.entry.alias << ")";
    out << ": " << e.entry.summary;
  }
  return out.str();
}

}  // namespace thinlod::backbone
