#include "thinlod/frontend/frame_record.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <utility>

namespace thinlod::frontend {
namespace {

// Empty for NaN, "inf"/"-inf" for infinities, else printf with `format`.
std::string formatNumber(double value, const char* format) {
  if (std::isnan(value)) return "";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Empty for -1 (not measured).
std::string formatCount(long value) { return value < 0 ? std::string() : std::to_string(value); }

nlohmann::json jsonNumber(double value) {
  if (std::isnan(value)) return nullptr;
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return value;
}

nlohmann::json jsonPercentiles(const Percentiles& p) {
  return nlohmann::json{{"count", p.count},
                        {"median", jsonNumber(p.median)},
                        {"p99", jsonNumber(p.p99)},
                        {"max", jsonNumber(p.max)}};
}

// Nearest rank: element ceil(q * n) - 1 of the sorted values, q in (0, 1].
double nearestRank(const std::vector<double>& sorted, double q) {
  const auto n = static_cast<double>(sorted.size());
  const auto rank = static_cast<std::size_t>(std::ceil(q * n));
  return sorted[std::max<std::size_t>(rank, 1) - 1];
}

// `values` finite; sorted in place.
Percentiles percentilesSorting(std::vector<double>& values) {
  Percentiles p;
  p.count = values.size();
  if (values.empty()) return p;
  std::sort(values.begin(), values.end());
  p.median = nearestRank(values, 0.5);
  p.p99 = nearestRank(values, 0.99);
  p.max = values.back();
  return p;
}

void addFinite(std::vector<double>& values, double value) {
  if (std::isfinite(value)) values.push_back(value);
}

void addMeasured(std::vector<double>& values, double value) {
  if (!std::isnan(value)) values.push_back(value);
}

Status ioError(const std::string& path, const std::string& what) {
  return Status(ErrorCode::kIoError, path + ": " + what);
}

}  // namespace

std::string frameCsvHeader() {
  return "frame,time_s,polygons,link_bytes,target_accuracy,snr_db,psnr_db,render_ms,"
         "pose_to_frame_ms,update_latency_ms,plan,draw_calls,uploaded_bytes,reference_ms,wait_ms,"
         "updates_received,updates_rejected,lockstep_timeout,shown_at_ms,visible_objects,"
         "missing_objects,blank,skinned_objects,deformed_vertices,pose_bytes,points,units,own_answer\n";
}

std::string formatFrameCsvRow(const FrameRecord& r) {
  std::string row;
  row.reserve(192);
  row += std::to_string(r.frame);
  row += ',' + formatNumber(r.timeS, "%.6f");
  row += ',' + std::to_string(r.polygons);
  row += ',' + std::to_string(r.linkBytes);
  row += ',' + formatNumber(r.targetAccuracy, "%.6g");
  row += ',' + formatNumber(r.quality.snrDb, "%.4f");
  row += ',' + formatNumber(r.quality.psnrDb, "%.4f");
  row += ',' + formatNumber(r.renderMs, "%.4f");
  row += ',' + formatNumber(r.poseToFrameMs, "%.4f");
  row += ',' + formatNumber(r.updateLatencyMs, "%.4f");
  row += ',' + std::to_string(r.plan);
  row += ',' + std::to_string(r.drawCalls);
  row += ',' + std::to_string(r.uploadedBytes);
  row += ',' + formatNumber(r.quality.referenceMs, "%.4f");
  row += ',' + formatNumber(r.waitMs, "%.4f");
  row += ',' + std::to_string(r.updatesReceived);
  row += ',' + std::to_string(r.updatesRejected);
  row += r.lockstepTimedOut ? ",1" : ",0";
  row += ',' + formatNumber(r.shownAtMs, "%.4f");
  row += ',' + formatCount(r.quality.visibleObjects);
  row += ',' + formatCount(r.quality.missingObjects);
  row += ',' + formatCount(r.quality.blank);
  row += ',' + std::to_string(r.skinnedObjects);
  row += ',' + std::to_string(r.deformedVertices);
  row += ',' + std::to_string(r.poseBytes);
  row += ',' + std::to_string(r.points);
  row += ',' + formatNumber(r.units, "%.2f");
  row += r.ownAnswer ? ",1" : ",0";
  row += '\n';
  return row;
}

double primitiveUnits(std::size_t triangles, std::size_t points, double kappa) {
  if (points == 0) return static_cast<double>(triangles);
  if (!(kappa > 0.0) || !std::isfinite(kappa)) return kMissingValue;
  return static_cast<double>(triangles) + static_cast<double>(points) / kappa;
}

std::string objectCsvHeader() {
  return "frame,time_s,object,kind,triangles,vertices,skinned,posed,x,y,z\n";
}

std::string formatObjectCsvRows(std::uint64_t frame, double timeS, const FrontendScene& scene) {
  std::string rows;
  const std::string prefix = std::to_string(frame) + ',' + formatNumber(timeS, "%.6f") + ',';
  for (const auto& [id, object] : scene.objects()) {
    const Representation& rep = object.representation;
    const bool skinned = rep.skin != nullptr;
    rows += prefix + std::to_string(id);
    rows += ',';
    rows += representationKindName(rep.kind);
    rows += ',' + std::to_string(object.triangleCount);
    rows += ',' + std::to_string(rep.mesh ? rep.mesh->vertexCount() : 0);
    rows += skinned ? ",1" : ",0";
    rows += skinned && scene.bonePose(id) != nullptr ? ",1" : ",0";
    for (int k = 0; k < 3; ++k) rows += ',' + formatNumber(rep.transform[3][k], "%.6g");
    rows += '\n';
  }
  return rows;
}

Percentiles percentiles(std::vector<double> values) {
  values.erase(
      std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
      values.end());
  return percentilesSorting(values);
}

void FrameSummary::add(const FrameRecord& r) {
  ++frames_;
  addFinite(renderMs_, r.renderMs);
  addFinite(poseToFrameMs_, r.poseToFrameMs);
  addFinite(updateLatencyMs_, r.updateLatencyMs);
  addFinite(referenceMs_, r.quality.referenceMs);
  addFinite(waitMs_, r.waitMs);
  addMeasured(snrDb_, r.quality.snrDb);
  addMeasured(psnrDb_, r.quality.psnrDb);
  polygonSum_ += static_cast<double>(r.polygons);
  polygonsMax_ = std::max(polygonsMax_, r.polygons);
  linkBytesTotal_ += r.linkBytes;
  if (r.ownAnswer) ++ownAnswerFrames_;
}

ReplaySummary FrameSummary::summarize() {
  ReplaySummary s;
  s.frames = frames_;
  s.renderMs = percentilesSorting(renderMs_);
  s.poseToFrameMs = percentilesSorting(poseToFrameMs_);
  s.updateLatencyMs = percentilesSorting(updateLatencyMs_);
  s.referenceMs = percentilesSorting(referenceMs_);
  s.waitMs = percentilesSorting(waitMs_);
  s.snrFrames = snrDb_.size();
  if (!snrDb_.empty()) {
    std::sort(snrDb_.begin(), snrDb_.end());
    s.snrMedianDb = nearestRank(snrDb_, 0.5);
    s.snrMinDb = snrDb_.front();
  }
  if (!psnrDb_.empty()) {
    std::sort(psnrDb_.begin(), psnrDb_.end());
    s.psnrMedianDb = nearestRank(psnrDb_, 0.5);
  }
  if (frames_ > 0) s.polygonsMean = polygonSum_ / static_cast<double>(frames_);
  s.polygonsMax = polygonsMax_;
  s.linkBytesTotal = linkBytesTotal_;
  s.ownAnswerFrames = ownAnswerFrames_;
  return s;
}

std::size_t FrameSummary::heldBytes() const {
  std::size_t values = 0;
  for (const std::vector<double>* v : {&renderMs_, &poseToFrameMs_, &updateLatencyMs_,
                                       &referenceMs_, &waitMs_, &snrDb_, &psnrDb_}) {
    values += v->capacity();
  }
  return values * sizeof(double);
}

std::string summaryJson(const ReplaySummary& s) {
  const nlohmann::json json{
      {"frames", s.frames},
      {"render_ms", jsonPercentiles(s.renderMs)},
      {"pose_to_frame_ms", jsonPercentiles(s.poseToFrameMs)},
      {"update_latency_ms", jsonPercentiles(s.updateLatencyMs)},
      {"reference_ms", jsonPercentiles(s.referenceMs)},
      {"wait_ms", jsonPercentiles(s.waitMs)},
      {"snr_db",
       {{"count", s.snrFrames},
        {"median", jsonNumber(s.snrMedianDb)},
        {"min", jsonNumber(s.snrMinDb)}}},
      {"psnr_db", {{"median", jsonNumber(s.psnrMedianDb)}}},
      {"polygons", {{"mean", jsonNumber(s.polygonsMean)}, {"max", s.polygonsMax}}},
      {"link_bytes_total", s.linkBytesTotal},
      {"own_answer_frames", s.ownAnswerFrames},
  };
  return json.dump(2);
}

Result<std::unique_ptr<FrameLog>> FrameLog::open(const std::string& csvPath) {
  std::FILE* csv = nullptr;
  if (!csvPath.empty()) {
    csv = std::fopen(csvPath.c_str(), "wb");
    if (csv == nullptr)
      return ioError(csvPath, std::string("cannot create (") + std::strerror(errno) + ")");
  }
  std::unique_ptr<FrameLog> log(new FrameLog(csvPath, csv));
  if (csv != nullptr) {
    const std::string header = frameCsvHeader();
    if (std::fwrite(header.data(), 1, header.size(), csv) != header.size() ||
        std::fflush(csv) != 0) {
      return ioError(csvPath, "cannot write the CSV header");
    }
  }
  return log;
}

FrameLog::~FrameLog() {
  if (csv_ != nullptr) std::fclose(csv_);
  if (spill_ != nullptr) std::fclose(spill_);
}

Status FrameLog::fail(Status status) {
  if (error_.ok()) error_ = status;
  return status;
}

Status FrameLog::add(const FrameRecord& record) {
  summary_.add(record);
  if (path_.empty()) return Status();
  if (csv_ == nullptr) return fail(ioError(path_, "already closed"));
  const std::string row = formatFrameCsvRow(record);
  if (std::fwrite(row.data(), 1, row.size(), csv_) != row.size() || std::fflush(csv_) != 0) {
    return fail(ioError(path_, "cannot write frame " + std::to_string(record.frame)));
  }
  return Status();
}

Status FrameLog::addPending(const FrameRecord& record) {
  if (pending_ > 0 && record.frame <= lastPendingFrame_) {
    return Status(ErrorCode::kInvalidArgument, "FrameLog::addPending: frame " +
                                                   std::to_string(record.frame) + " after frame " +
                                                   std::to_string(lastPendingFrame_));
  }
  if (spill_ == nullptr) {
    spill_ = std::tmpfile();
    if (spill_ == nullptr) {
      return fail(
          ioError(path_ + " (pending rows)",
                  std::string("cannot create a temporary file (") + std::strerror(errno) + ")"));
    }
  }
  if (std::fwrite(&record, sizeof record, 1, spill_) != 1) {
    return fail(
        ioError(path_ + " (pending rows)", "cannot spill frame " + std::to_string(record.frame)));
  }
  ++pending_;
  lastPendingFrame_ = record.frame;
  return Status();
}

Status FrameLog::applyScores(const std::vector<FrameScore>& scores,
                             const std::function<void(const FrameRecord&)>& onRecord) {
  for (std::size_t k = 1; k < scores.size(); ++k) {
    if (scores[k].frame <= scores[k - 1].frame) {
      return Status(ErrorCode::kInvalidArgument,
                    "FrameLog::applyScores: scores not ascending at frame " +
                        std::to_string(scores[k].frame));
    }
  }
  if (pending_ == 0) return Status();
  if (std::fflush(spill_) != 0 || std::fseek(spill_, 0, SEEK_SET) != 0) {
    return fail(ioError(path_ + " (pending rows)", "cannot rewind the temporary file"));
  }
  Status status;
  auto score = scores.begin();
  for (std::size_t k = 0; k < pending_; ++k) {
    FrameRecord record;
    if (std::fread(&record, sizeof record, 1, spill_) != 1) {
      status = fail(
          ioError(path_ + " (pending rows)", "cannot read pending record " + std::to_string(k)));
      break;
    }
    while (score != scores.end() && score->frame < record.frame) ++score;
    if (score != scores.end() && score->frame == record.frame) record.quality = score->quality;
    if (onRecord) onRecord(record);
    const Status added = add(record);
    if (status.ok() && !added.ok()) status = added;
  }
  std::fclose(spill_);
  spill_ = nullptr;
  pending_ = 0;
  return status;
}

Status FrameLog::close() {
  if (spill_ != nullptr) {
    std::fclose(spill_);
    spill_ = nullptr;
    pending_ = 0;
  }
  if (csv_ != nullptr) {
    const int closed = std::fclose(csv_);
    csv_ = nullptr;
    if (closed != 0) (void)fail(ioError(path_, "cannot close"));
  }
  return error_;
}

}  // namespace thinlod::frontend
