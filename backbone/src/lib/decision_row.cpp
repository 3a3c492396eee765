#include "thinlod/backbone/decision_row.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <string>

#include "thinlod/backbone/pipeline.h"
#include "thinlod/backbone/scheduler.h"
#include "thinlod/backbone/scheduling_scene.h"

namespace thinlod::backbone {
namespace {

void appendNumber(std::string& out, double v) {
  char buffer[40];
  if (std::isnan(v)) {
    out += "nan";
  } else if (std::isinf(v)) {
    out += v > 0 ? "inf" : "-inf";
  } else {
    std::snprintf(buffer, sizeof buffer, "%.9g", v);
    out += buffer;
  }
}

void appendCount(std::string& out, std::uint64_t v) {
  char buffer[24];
  std::snprintf(buffer, sizeof buffer, "%" PRIu64, v);
  out += buffer;
}

}  // namespace

std::string decisionRowCsvHeader() {
  return "frame,time_s,scheduler,mode,target_accuracy,achieved_min_accuracy,predicted_triangles,"
         "link_bytes_step,link_bytes_per_s,visible_objects,requests,sends,keeps,removals,"
         "below_target,dropped,curve_reuses,scheduling_us";
}

std::string decisionRowCsv(const DecisionRow& r) {
  std::string out;
  out.reserve(192);
  appendCount(out, r.frame);
  out += ',';
  appendNumber(out, r.timeSeconds);
  out += ',';
  out += r.scheduler ? r.scheduler : "";
  out += ',';
  out += r.mode ? r.mode : "";
  for (double v : {r.targetAccuracy, r.achievedMinAccuracy, r.predictedTriangles,
                   r.linkBytesThisStep, r.linkBytesPerSecond}) {
    out += ',';
    appendNumber(out, v);
  }
  for (std::uint32_t v : {r.visibleObjects, r.requests, r.sends, r.keeps, r.removals, r.belowTarget,
                          r.dropped, r.curveReuses}) {
    out += ',';
    appendCount(out, v);
  }
  out += ',';
  appendNumber(out, r.schedulingMicroseconds);
  return out;
}

std::string objectDecisionCsvHeader() {
  return "frame,time_s,object,action,option,kind,source,relative_accuracy,absolute_accuracy,"
         "triangles,link_bytes,below_target";
}

std::string objectDecisionCsv(std::uint64_t frame, double timeSeconds, const ObjectDecision& d) {
  std::string out;
  out.reserve(128);
  appendCount(out, frame);
  out += ',';
  appendNumber(out, timeSeconds);
  out += ',';
  appendCount(out, d.object);
  out += ',';
  out += objectActionName(d.action);
  out += ',';
  // -1: no option (a removal); kind and source then say nothing.
  out += std::to_string(d.option);
  out += ',';
  out += d.option >= 0 ? optionKindName(d.kind) : "";
  out += ',';
  out += d.option >= 0 ? candidateSourceName(d.source) : "";
  for (double v : {d.relativeAccuracy, d.absoluteAccuracy, d.triangles, d.linkBytes}) {
    out += ',';
    appendNumber(out, v);
  }
  out += d.belowTarget ? ",1" : ",0";
  return out;
}

}  // namespace thinlod::backbone
