// One frame's numbers and the one writer of a run's per-frame CSV
// (frames.csv) and summary (docs/frontend.md, "Per-frame CSV and summary").
//
// Contract:
// - FrameRecord is the only per-frame record: it holds every column of
//   frames.csv, in frameCsvHeader() order. FrameQuality (what measuring the
//   frame against its reference gives) is one member of it, filled whole by
//   the producer or a deferred FrameScore; protocol::FrameStats is made from a
//   record in one place (daemon, wire_conversion.h).
// - Units: time_s = trace time of the frame's pose (seconds); *_ms =
//   milliseconds of wall-clock time; link_bytes = bytes received from the
//   backbone since the previous frame; target_accuracy = the plan's target
//   (1/rad, as the backbone defines it); snr_db/psnr_db as frame_metrics.h.
//   Each column's meaning: docs/frontend.md, "Columns and their exact meaning".
// - Missing values are NaN (counts: -1): an empty CSV field and JSON null.
//   Infinite SNR/PSNR (identical frames) is written "inf" / "-inf" in both.
// - Percentiles are nearest-rank over the finite values: the p-th of n
//   sorted values is element ceil(p/100 * n) - 1; the median is p = 50 (the
//   lower middle for even n). min/median of SNR and PSNR include infinities.
// - Memory: FrameSummary keeps no records, only the values its quantiles
//   need: at most 7 doubles per frame (render, pose-to-frame, update-latency,
//   reference and wait ms when finite; SNR and PSNR when measured), i.e.
//   <= 56 bytes per frame plus vector slack (< 2x), and O(1) counters. Its
//   summary equals summarizing all records at once. FrameLog adds nothing per
//   frame: rows go to the file as they come, and records awaiting a deferred
//   score go to an anonymous temporary file (sizeof(FrameRecord) bytes each on
//   disk, none in memory) until applyScores().
// - formatFrameCsvRow / frameCsvHeader / summaryJson / percentiles are pure and
//   thread-safe. FrameSummary and FrameLog are not thread-safe; FrameLog's I/O
//   failures are kIoError naming the path (the first one sticks).
// - Per object (objects.csv, thinlod-frontend --objects-csv): formatObjectCsvRows
//   gives one row per object the scene holds, in id order, for the frame just
//   drawn (pure; the scene is only read).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "thinlod/common/core/status.h"
#include "thinlod/frontend/frontend_scene.h"

namespace thinlod::frontend {

inline constexpr double kMissingValue = std::numeric_limits<double>::quiet_NaN();

// A frame measured against the full-quality reference of its pose.
struct FrameQuality {
  double snrDb = kMissingValue;
  double psnrDb = kMissingValue;
  double referenceMs = kMissingValue;  // the reference's render time
  // Completeness (shown_frames.h): -1 = not measured.
  long visibleObjects = -1;  // object groups in the view volume
  long missingObjects = -1;  // of those, groups the frontend held nothing of
  int blank = -1;            // 1: the shown frame is uniform, the reference is not
};

// A deferred measurement: the quality of frame `frame`, known after the replay.
struct FrameScore {
  std::uint64_t frame = 0;
  FrameQuality quality;
};

struct FrameRecord {
  static constexpr double kMissing = kMissingValue;
  std::uint64_t frame = 0;
  double timeS = 0.0;
  std::size_t polygons = 0;
  std::uint64_t linkBytes = 0;
  double targetAccuracy = kMissing;
  double renderMs = kMissing;
  double poseToFrameMs = kMissing;
  double updateLatencyMs = kMissing;
  std::uint64_t plan = 0;  // last applied SceneUpdate plan
  // Of polygons, first representations shown before their plan (not in the
  // CSV; FrameStats.early_polygons).
  std::size_t earlyPolygons = 0;
  std::size_t drawCalls = 0;
  std::size_t uploadedBytes = 0;  // representation bytes uploaded to the GPU this frame
  double waitMs = 0.0;            // pose sent -> render started (lockstep wait or poll)
  std::size_t updatesReceived = 0;
  std::size_t updatesRejected = 0;
  bool lockstepTimedOut = false;
  double shownAtMs = kMissing;  // readback done, ms after frame 0's pose was sampled
  // Skinned objects drawn and the vertices of their levels the vertex
  // shader deformed (FrameReport; docs/animation.md).
  std::size_t skinnedObjects = 0;
  std::size_t deformedVertices = 0;
  // Bone-pose bytes of the updates received since the previous frame (48 a
  // matrix, as payloadBytes counts them): the part of link_bytes that is
  // poses rather than geometry, textures or framing.
  std::uint64_t poseBytes = 0;
  // Hybrid disc points drawn (FrameReport::discs) and the frame's primitive
  // units, triangles + points / kappa (primitiveUnits; the unit the
  // backbone's polygon budget counts when hybrids are on).
  std::size_t points = 0;
  double units = kMissing;
  // The backbone's answer to this frame's own pose (SceneUpdate.frame ==
  // frame) had arrived when the frame was drawn; false on a frame that sent
  // no pose. Live without --answer-wait-ms it depends on the planning time
  // (docs/frontend.md, "Answer wait").
  bool ownAnswer = false;
  FrameQuality quality;  // snr_db, psnr_db, reference_ms, visible/missing, blank
};
// FrameLog spills pending records as raw bytes.
static_assert(std::is_trivially_copyable_v<FrameRecord>);

// "frame,time_s,polygons,link_bytes,target_accuracy,snr_db,psnr_db,render_ms,
//  pose_to_frame_ms,update_latency_ms,plan,draw_calls,uploaded_bytes,
//  reference_ms,wait_ms,updates_received,updates_rejected,lockstep_timeout,
//  shown_at_ms,visible_objects,missing_objects,blank,skinned_objects,
//  deformed_vertices,pose_bytes,points,units,own_answer\n"
std::string frameCsvHeader();
// One line, '\n'-terminated, columns as in the header.
std::string formatFrameCsvRow(const FrameRecord& record);

// Primitive units of a frame that drew `triangles` and `points` hybrid discs:
// `triangles` when there are no points (whatever kappa), triangles + points /
// kappa when kappa > 0 (the backbone's --hybrid-kappa), else missing (NaN:
// points drawn at an unknown price).
double primitiveUnits(std::size_t triangles, std::size_t points, double kappa);

// "frame,time_s,object,kind,triangles,vertices,skinned,posed,x,y,z\n": per
// held object, its representation's kind (representationKindName), triangles
// and mesh vertices; skinned 1 when it carries a skin, posed 1 when the scene
// also holds a bone pose for it (then the renderer deforms its `vertices`,
// unless the pose has fewer bones than the skin names); x, y, z the
// translation of its object -> world transform (which object it is).
std::string objectCsvHeader();
// The rows of every object `scene` holds, ascending by id ("" when none).
std::string formatObjectCsvRows(std::uint64_t frame, double timeS, const FrontendScene& scene);

struct Percentiles {
  std::size_t count = 0;  // finite values used
  double median = kMissingValue;
  double p99 = kMissingValue;
  double max = kMissingValue;
};
// Drops non-finite values.
Percentiles percentiles(std::vector<double> values);

struct ReplaySummary {
  std::size_t frames = 0;
  Percentiles renderMs;
  Percentiles poseToFrameMs;
  Percentiles updateLatencyMs;
  Percentiles referenceMs;
  Percentiles waitMs;
  std::size_t snrFrames = 0;  // frames with a measured SNR (infinite included)
  double snrMedianDb = kMissingValue;
  double snrMinDb = kMissingValue;
  double psnrMedianDb = kMissingValue;
  double polygonsMean = kMissingValue;
  std::size_t polygonsMax = 0;
  std::uint64_t linkBytesTotal = 0;
  std::size_t ownAnswerFrames = 0;  // frames drawn with their own pose's answer
};

// A run's summary, accumulated frame by frame (memory: see the contract).
class FrameSummary {
 public:
  void add(const FrameRecord& record);
  // Sorts the kept values in place; add() may go on afterwards.
  ReplaySummary summarize();
  std::size_t frames() const { return frames_; }
  // Heap bytes held for the quantiles (vector capacities).
  std::size_t heldBytes() const;

 private:
  std::size_t frames_ = 0;
  double polygonSum_ = 0.0;
  std::size_t polygonsMax_ = 0;
  std::uint64_t linkBytesTotal_ = 0;
  std::size_t ownAnswerFrames_ = 0;
  std::vector<double> renderMs_, poseToFrameMs_, updateLatencyMs_, referenceMs_, waitMs_;
  std::vector<double> snrDb_, psnrDb_;  // measured: infinities kept, NaN dropped
};

// A JSON object (nlohmann_json), indented by 2: frames, render_ms,
// pose_to_frame_ms, update_latency_ms, reference_ms, wait_ms ({count, median,
// p99, max}), snr_db {count, median, min}, psnr_db {median}, polygons {mean,
// max}, link_bytes_total, own_answer_frames.
std::string summaryJson(const ReplaySummary& summary);

// frames.csv and the summary of one run.
class FrameLog {
 public:
  // Creates/truncates `csvPath` and writes the header; "" = no CSV (summary only).
  static Result<std::unique_ptr<FrameLog>> open(const std::string& csvPath);
  ~FrameLog();
  FrameLog(const FrameLog&) = delete;
  FrameLog& operator=(const FrameLog&) = delete;

  // A finished record: its row (flushed, so a crash loses little) and the summary.
  Status add(const FrameRecord& record);
  // A record whose quality comes later (deferred scoring): spilled to a
  // temporary file. Pending records must come in frame order.
  Status addPending(const FrameRecord& record);
  // Reads the pending records back in order, sets each one's quality from the
  // score with its frame number (scores ascending by frame; records without
  // one keep theirs), calls `onRecord` with it and add()s it.
  Status applyScores(const std::vector<FrameScore>& scores,
                     const std::function<void(const FrameRecord&)>& onRecord = {});
  std::size_t pendingRecords() const { return pending_; }

  FrameSummary& summary() { return summary_; }
  // The first I/O error so far (ok when none).
  const Status& error() const { return error_; }
  // Closes the CSV (pending records are dropped); returns error() or the close's error.
  Status close();

 private:
  FrameLog(std::string path, std::FILE* csv) : path_(std::move(path)), csv_(csv) {}
  Status fail(Status status);
  std::string path_;
  std::FILE* csv_;
  std::FILE* spill_ = nullptr;  // pending records (tmpfile), opened on first use
  std::size_t pending_ = 0;
  std::uint64_t lastPendingFrame_ = 0;
  FrameSummary summary_;
  Status error_;
};

}  // namespace thinlod::frontend
