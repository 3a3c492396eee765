// DecisionRow: one line of the backbone's decision log per planning step.
//
// Contract:
// - Units: accuracy rad^-1, polygons in triangles, link in bytes (this step)
//   and bytes/s (amortised over the planned lifetime), time in microseconds.
// - decisionRowCsv() formats one row without a trailing newline; the column
//   order is decisionRowCsvHeader(). No I/O: the daemon writes the lines.
// - Non-finite accuracies print as "inf" / "nan" so a row always has the
//   same number of columns.
// - objectDecisionCsv() is the per-object companion: one row per object
//   decision of a plan (what was chosen for it, where from, at what
//   accuracy and cost), columns in objectDecisionCsvHeader() order.
#pragma once

#include <cstdint>
#include <string>

namespace thinlod::backbone {

struct ObjectDecision;  // scheduler.h, which includes this header

struct DecisionRow {
  std::uint64_t frame = 0;
  double timeSeconds = 0.0;
  const char* scheduler = "";
  const char* mode = "";
  double targetAccuracy = 0.0;
  double achievedMinAccuracy = 0.0;  // lowest guaranteed accuracy over visible objects
  double predictedTriangles = 0.0;
  double linkBytesThisStep = 0.0;
  double linkBytesPerSecond = 0.0;
  std::uint32_t visibleObjects = 0;
  std::uint32_t requests = 0;
  std::uint32_t sends = 0;
  std::uint32_t keeps = 0;
  std::uint32_t removals = 0;
  std::uint32_t belowTarget = 0;
  std::uint32_t dropped = 0;
  std::uint32_t curveReuses = 0;
  double schedulingMicroseconds = 0.0;
};

std::string decisionRowCsvHeader();
std::string decisionRowCsv(const DecisionRow& row);

std::string objectDecisionCsvHeader();
std::string objectDecisionCsv(std::uint64_t frame, double timeSeconds, const ObjectDecision& d);

}  // namespace thinlod::backbone
