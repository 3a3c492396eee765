// Frame records: CSV formatting, percentiles, the bounded summary and its
// JSON, FrameLog (rows streamed, deferred scores merged from a spill file).
#include "thinlod/frontend/frame_record.h"

#include <gtest/gtest.h>
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "frontend_test_util.h"

namespace thinlod::frontend {
namespace {

const double kInf = std::numeric_limits<double>::infinity();

FrameRecord sampleRecord() {
  FrameRecord r;
  r.frame = 12;
  r.timeS = 0.4;
  r.polygons = 348;
  r.linkBytes = 262144;
  r.targetAccuracy = 200.0;
  r.quality.snrDb = 11.25;
  r.quality.psnrDb = 30.5;
  r.renderMs = 2.6;
  r.poseToFrameMs = 7.125;
  r.updateLatencyMs = 31.5;
  r.plan = 3;
  r.drawCalls = 2;
  r.uploadedBytes = 524288;
  r.quality.referenceMs = 20.25;
  r.waitMs = 3.5;
  r.updatesReceived = 1;
  r.updatesRejected = 0;
  r.lockstepTimedOut = true;
  r.shownAtMs = 400.125;
  r.quality.visibleObjects = 7;
  r.quality.missingObjects = 2;
  r.quality.blank = 0;
  return r;
}

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "thinlod_frontend_" + std::to_string(::getpid()) + "_" + name;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(FrameRecord, HeaderHasTheRequiredColumnsInOrder) {
  EXPECT_EQ(frameCsvHeader(),
            "frame,time_s,polygons,link_bytes,target_accuracy,snr_db,psnr_db,render_ms,"
            "pose_to_frame_ms,update_latency_ms,plan,draw_calls,uploaded_bytes,reference_ms,"
            "wait_ms,updates_received,updates_rejected,lockstep_timeout,shown_at_ms,"
            "visible_objects,missing_objects,blank,skinned_objects,deformed_vertices,"
            "pose_bytes,points,units,own_answer\n");
}

TEST(FrameRecord, RowFormatsEveryColumn) {
  EXPECT_EQ(formatFrameCsvRow(sampleRecord()),
            "12,0.400000,348,262144,200,11.2500,30.5000,2.6000,7.1250,31.5000,3,2,524288,"
            "20.2500,3.5000,1,0,1,400.1250,7,2,0,0,0,0,0,,0\n");
}

TEST(FrameRecord, SkinnedColumnsComeLastAfterTheOlderOnes) {
  FrameRecord r = sampleRecord();
  r.skinnedObjects = 3;
  r.deformedVertices = 4453;
  r.poseBytes = 3 * 37 * 48;
  const std::string row = formatFrameCsvRow(r);
  EXPECT_EQ(row.substr(row.find(",400.1250,")), ",400.1250,7,2,0,3,4453,5328,0,,0\n");
}

TEST(FrameRecord, PointsAndUnitsComeAfterPoseBytes) {
  FrameRecord r = sampleRecord();
  r.poseBytes = 96;
  r.points = 30;
  r.units = primitiveUnits(r.polygons, r.points, 1.5);
  const std::string row = formatFrameCsvRow(r);
  EXPECT_EQ(row.substr(row.find(",400.1250,")), ",400.1250,7,2,0,0,0,96,30,368.00,0\n");
}

TEST(FrameRecord, OwnAnswerComesLast) {
  FrameRecord r = sampleRecord();
  r.ownAnswer = true;
  const std::string row = formatFrameCsvRow(r);
  EXPECT_EQ(row.substr(row.find(",400.1250,")), ",400.1250,7,2,0,0,0,0,0,,1\n");
}

TEST(FrameRecord, UnitsAreTrianglesPlusPointsOverKappa) {
  EXPECT_EQ(primitiveUnits(348, 30, 1.5), 368.0);
  EXPECT_EQ(primitiveUnits(100, 25, 10.0), 102.5);
  // No points: the triangles, whether kappa is known or not.
  EXPECT_EQ(primitiveUnits(348, 0, 0.0), 348.0);
  EXPECT_EQ(primitiveUnits(0, 0, 3.0), 0.0);
  // Points at an unknown price: missing, never the triangles alone.
  EXPECT_TRUE(std::isnan(primitiveUnits(348, 30, 0.0)));
  EXPECT_TRUE(std::isnan(primitiveUnits(348, 30, FrameRecord::kMissing)));
}

TEST(FrameRecord, MissingValuesAreEmptyAndInfinitiesSpelledOut) {
  FrameRecord r;
  r.frame = 1;
  r.quality.snrDb = kInf;
  r.quality.psnrDb = kInf;
  EXPECT_EQ(formatFrameCsvRow(r), "1,0.000000,0,0,,inf,inf,,,,0,0,0,,0.0000,0,0,0,,,,,0,0,0,0,,0\n");
  r.quality.snrDb = -kInf;
  EXPECT_NE(formatFrameCsvRow(r).find(",-inf,"), std::string::npos);
}

TEST(FrameRecord, PercentilesAreNearestRank) {
  std::vector<double> values;
  for (int i = 100; i >= 1; --i) values.push_back(i);
  const Percentiles p = percentiles(values);
  EXPECT_EQ(p.count, 100u);
  EXPECT_EQ(p.median, 50.0);
  EXPECT_EQ(p.p99, 99.0);
  EXPECT_EQ(p.max, 100.0);
}

TEST(FrameRecord, PercentilesOfFewValues) {
  const Percentiles one = percentiles({4.0});
  EXPECT_EQ(one.median, 4.0);
  EXPECT_EQ(one.p99, 4.0);
  const Percentiles two = percentiles({9.0, 1.0});
  EXPECT_EQ(two.median, 1.0);  // lower middle
  EXPECT_EQ(two.p99, 9.0);
}

TEST(FrameRecord, PercentilesDropNonFiniteValues) {
  const Percentiles p = percentiles({1.0, FrameRecord::kMissing, kInf, 3.0});
  EXPECT_EQ(p.count, 2u);
  EXPECT_EQ(p.max, 3.0);
  const Percentiles none = percentiles({FrameRecord::kMissing});
  EXPECT_EQ(none.count, 0u);
  EXPECT_TRUE(std::isnan(none.median));
}

ReplaySummary summarize(const std::vector<FrameRecord>& records) {
  FrameSummary summary;
  for (const FrameRecord& r : records) summary.add(r);
  return summary.summarize();
}

TEST(FrameSummary, CountsSnrWithInfinities) {
  std::vector<FrameRecord> records(5, sampleRecord());
  records[0].quality.snrDb = 8.0;
  records[1].quality.snrDb = kInf;
  records[2].quality.snrDb = 12.0;
  records[3].quality.snrDb = FrameRecord::kMissing;  // not measured
  records[4].quality.snrDb = 0.0;
  records[4].polygons = 400;
  records[2].renderMs = 9.0;
  records[3].quality.referenceMs = FrameRecord::kMissing;
  const ReplaySummary s = summarize(records);
  EXPECT_EQ(s.frames, 5u);
  EXPECT_EQ(s.snrFrames, 4u);
  EXPECT_EQ(s.snrMinDb, 0.0);
  EXPECT_EQ(s.snrMedianDb, 8.0);  // sorted {0, 8, 12, inf}: element ceil(2) - 1
  EXPECT_EQ(s.renderMs.median, 2.6);
  EXPECT_EQ(s.renderMs.max, 9.0);
  EXPECT_EQ(s.referenceMs.count, 4u);
  EXPECT_EQ(s.waitMs.count, 5u);
  EXPECT_EQ(s.polygonsMax, 400u);
  EXPECT_DOUBLE_EQ(s.polygonsMean, (4 * 348.0 + 400.0) / 5.0);
  EXPECT_EQ(s.linkBytesTotal, 5u * 262144u);
}

TEST(FrameSummary, EmptySummaryHasNoValues) {
  const ReplaySummary s = summarize({});
  EXPECT_EQ(s.frames, 0u);
  EXPECT_TRUE(std::isnan(s.snrMedianDb));
  EXPECT_TRUE(std::isnan(s.polygonsMean));
  EXPECT_EQ(s.renderMs.count, 0u);
}

TEST(FrameSummary, AddingAfterSummarizingCountsEveryFrame) {
  FrameSummary summary;
  FrameRecord r = sampleRecord();
  r.renderMs = 5.0;
  summary.add(r);
  EXPECT_EQ(summary.summarize().renderMs.max, 5.0);
  r.renderMs = 1.0;
  summary.add(r);
  summary.add(r);
  const ReplaySummary s = summary.summarize();
  EXPECT_EQ(s.frames, 3u);
  EXPECT_EQ(s.renderMs.median, 1.0);
  EXPECT_EQ(s.renderMs.max, 5.0);
}

TEST(FrameSummary, JsonRoundTrips) {
  std::vector<FrameRecord> records(3, sampleRecord());
  records[1].quality.snrDb = kInf;
  records[2].poseToFrameMs = FrameRecord::kMissing;
  records[0].updateLatencyMs = 12.0;
  records[1].updateLatencyMs = FrameRecord::kMissing;
  const nlohmann::json json = nlohmann::json::parse(summaryJson(summarize(records)));
  EXPECT_EQ(json["frames"], 3);
  EXPECT_EQ(json["render_ms"]["median"], 2.6);
  EXPECT_EQ(json["render_ms"]["p99"], 2.6);
  EXPECT_EQ(json["pose_to_frame_ms"]["count"], 2);
  EXPECT_EQ(json["update_latency_ms"]["count"], 2);
  EXPECT_EQ(json["update_latency_ms"]["median"], 12.0);
  EXPECT_EQ(json["update_latency_ms"]["max"], 31.5);
  EXPECT_EQ(json["reference_ms"]["median"], 20.25);
  EXPECT_EQ(json["wait_ms"]["count"], 3);
  EXPECT_EQ(json["snr_db"]["median"], 11.25);
  EXPECT_EQ(json["snr_db"]["min"], 11.25);
  EXPECT_EQ(json["snr_db"]["count"], 3);
  EXPECT_EQ(json["link_bytes_total"], 3 * 262144);
  EXPECT_EQ(json["own_answer_frames"], 0);
  records[0].ownAnswer = true;
  records[2].ownAnswer = true;
  EXPECT_EQ(nlohmann::json::parse(summaryJson(summarize(records)))["own_answer_frames"], 2);
}

TEST(FrameSummary, JsonSpellsInfinityAndNull) {
  std::vector<FrameRecord> records(1, sampleRecord());
  records[0].quality.snrDb = kInf;
  records[0].quality.psnrDb = kInf;
  records[0].poseToFrameMs = FrameRecord::kMissing;
  const nlohmann::json json = nlohmann::json::parse(summaryJson(summarize(records)));
  EXPECT_EQ(json["snr_db"]["median"], "inf");
  EXPECT_EQ(json["psnr_db"]["median"], "inf");
  EXPECT_TRUE(json["pose_to_frame_ms"]["median"].is_null());
}

TEST(FrameLog, WritesHeaderAndRowsAsTheyCome) {
  const std::string path = tempPath("frames.csv");
  auto log = FrameLog::open(path);
  ASSERT_TRUE(log.ok()) << log.status().toString();
  ASSERT_TRUE((*log)->add(sampleRecord()).ok());
  // Flushed per row: on disk before the log is closed.
  EXPECT_EQ(readFile(path), frameCsvHeader() + formatFrameCsvRow(sampleRecord()));
  FrameRecord second = sampleRecord();
  second.frame = 13;
  ASSERT_TRUE((*log)->add(second).ok());
  ASSERT_TRUE((*log)->close().ok());
  EXPECT_EQ((*log)->add(second).code(), ErrorCode::kIoError);  // closed
  EXPECT_EQ((*log)->close().code(), ErrorCode::kIoError);      // the first error sticks
  EXPECT_EQ(readFile(path),
            frameCsvHeader() + formatFrameCsvRow(sampleRecord()) + formatFrameCsvRow(second));
  EXPECT_EQ((*log)->summary().frames(), 3u);  // the summary still counts what was given
  std::remove(path.c_str());
}

TEST(FrameLog, ReportsAnUnwritablePath) {
  auto log = FrameLog::open("/nonexistent-dir/frames.csv");
  ASSERT_FALSE(log.ok());
  EXPECT_EQ(log.status().code(), ErrorCode::kIoError);
  EXPECT_NE(log.status().message().find("/nonexistent-dir/frames.csv"), std::string::npos);
}

TEST(FrameLog, WithoutAPathOnlySummarizes) {
  auto log = FrameLog::open("");
  ASSERT_TRUE(log.ok());
  ASSERT_TRUE((*log)->add(sampleRecord()).ok());
  ASSERT_TRUE((*log)->close().ok());
  EXPECT_EQ((*log)->summary().summarize().renderMs.median, 2.6);
}

TEST(FrameLog, PendingRecordsGetTheirScoresByFrameNumberAndAreWrittenInOrder) {
  const std::string path = tempPath("pending.csv");
  auto log = FrameLog::open(path);
  ASSERT_TRUE(log.ok());
  std::vector<FrameRecord> records;
  for (std::uint64_t i = 0; i < 5; ++i) {
    FrameRecord r;
    r.frame = i;
    r.renderMs = 1.0 + static_cast<double>(i);
    records.push_back(r);
    ASSERT_TRUE((*log)->addPending(r).ok());
  }
  EXPECT_EQ(readFile(path), frameCsvHeader());  // nothing written before the scores
  EXPECT_EQ((*log)->pendingRecords(), 5u);
  EXPECT_EQ((*log)->summary().frames(), 0u);
  // Frames 1 and 3 were not kept: no score, their quality stays missing.
  std::vector<FrameScore> scores;
  for (std::uint64_t i : {0u, 2u, 4u}) {
    FrameScore score;
    score.frame = i;
    score.quality.snrDb = 10.0 * static_cast<double>(i);
    score.quality.blank = 0;
    scores.push_back(score);
  }
  std::vector<std::uint64_t> seen;
  ASSERT_TRUE(
      (*log)->applyScores(scores, [&](const FrameRecord& r) { seen.push_back(r.frame); }).ok());
  EXPECT_EQ(seen, (std::vector<std::uint64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ((*log)->pendingRecords(), 0u);
  ASSERT_TRUE((*log)->close().ok());
  std::string expected = frameCsvHeader();
  for (FrameRecord r : records) {
    if (r.frame % 2 == 0) r.quality = scores[r.frame / 2].quality;
    expected += formatFrameCsvRow(r);
  }
  EXPECT_EQ(readFile(path), expected);
  const ReplaySummary s = (*log)->summary().summarize();
  EXPECT_EQ(s.frames, 5u);
  EXPECT_EQ(s.snrFrames, 3u);
  EXPECT_EQ(s.snrMedianDb, 20.0);
  std::remove(path.c_str());
}

TEST(FrameLog, RefusesPendingRecordsOutOfOrderAndScoresNotAscending) {
  auto log = FrameLog::open("");
  ASSERT_TRUE(log.ok());
  FrameRecord r;
  r.frame = 4;
  ASSERT_TRUE((*log)->addPending(r).ok());
  r.frame = 4;
  EXPECT_EQ((*log)->addPending(r).code(), ErrorCode::kInvalidArgument);
  std::vector<FrameScore> scores(2);
  scores[0].frame = 5;
  scores[1].frame = 2;
  EXPECT_EQ((*log)->applyScores(scores).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ((*log)->pendingRecords(), 1u);  // still pending, nothing lost
  EXPECT_TRUE((*log)->applyScores({}).ok());
  EXPECT_EQ((*log)->summary().frames(), 1u);
}

// Heap bytes in use: the arena's plus mmap'ed chunks (large vectors live there).
std::size_t heapInUse() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
}

// A synthetic frame i, the same on every call (seeded by i).
FrameRecord syntheticFrame(std::uint64_t i) {
  std::mt19937_64 random(0x5eed0000 + i);
  std::uniform_real_distribution<double> ms(0.1, 50.0);
  FrameRecord r;
  r.frame = i;
  r.timeS = static_cast<double>(i) / 60.0;
  r.polygons = random() % 400;
  r.linkBytes = random() % 100000;
  r.renderMs = ms(random);
  r.poseToFrameMs = i % 7 == 0 ? FrameRecord::kMissing : ms(random);  // redraws
  r.updateLatencyMs = i % 3 == 0 ? ms(random) : FrameRecord::kMissing;
  r.waitMs = ms(random);
  r.quality.referenceMs = ms(random);
  r.quality.snrDb = i % 1000 == 0 ? kInf : ms(random) - 10.0;
  r.quality.psnrDb = ms(random);
  return r;
}

// Nearest rank over all finite values, computed independently of FrameSummary.
Percentiles expectedPercentiles(std::vector<double> values) {
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  std::sort(finite.begin(), finite.end());
  Percentiles p;
  p.count = finite.size();
  const auto rank = [&](double q) {
    std::size_t k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(finite.size())));
    return finite[std::max<std::size_t>(k, 1) - 1];
  };
  p.median = rank(0.5);
  p.p99 = rank(0.99);
  p.max = finite.back();
  return p;
}

void expectSamePercentiles(const Percentiles& actual, const Percentiles& expected,
                           const char* what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(actual.count, expected.count);
  EXPECT_EQ(actual.median, expected.median);
  EXPECT_EQ(actual.p99, expected.p99);
  EXPECT_EQ(actual.max, expected.max);
}

// A long run through the writer: 100k frames (about half an hour at 60 frames/s).
// The heap it holds grows by the summary's doubles only, never by records,
// and the summary equals one computed from every value.
TEST(FrameLog, ALongRunKeepsMemoryPerFrameSmallAndTheSummaryExact) {
  constexpr std::uint64_t kFrames = 100'000;
  const std::string path = tempPath("long.csv");
  const std::size_t heapBefore = heapInUse();
  auto log = FrameLog::open(path);
  ASSERT_TRUE(log.ok());
  for (std::uint64_t i = 0; i < kFrames; ++i) ASSERT_TRUE((*log)->add(syntheticFrame(i)).ok());
  const std::size_t heapDuring = heapInUse();
  const double bytesPerFrame =
      static_cast<double>(heapDuring - std::min(heapBefore, heapDuring)) / kFrames;
  // 7 doubles at most (56 bytes) plus vector slack; a kept FrameRecord alone
  // would be sizeof(FrameRecord) per frame.
  RecordProperty("heap_bytes_per_frame", std::to_string(bytesPerFrame));
  RecordProperty("sizeof_frame_record", std::to_string(sizeof(FrameRecord)));
  EXPECT_LE(bytesPerFrame, 2.0 * 7 * sizeof(double)) << bytesPerFrame << " bytes per frame";
  EXPECT_LT(bytesPerFrame, static_cast<double>(sizeof(FrameRecord)));
  EXPECT_LE((*log)->summary().heldBytes(), std::size_t{2} * 7 * sizeof(double) * kFrames);
  ASSERT_TRUE((*log)->close().ok());
  const ReplaySummary s = (*log)->summary().summarize();

  std::vector<double> render, poseToFrame, updateLatency, reference, wait, snr, psnr;
  double polygonSum = 0.0;
  std::size_t polygonsMax = 0;
  std::uint64_t linkBytes = 0;
  for (std::uint64_t i = 0; i < kFrames; ++i) {
    const FrameRecord r = syntheticFrame(i);
    render.push_back(r.renderMs);
    poseToFrame.push_back(r.poseToFrameMs);
    updateLatency.push_back(r.updateLatencyMs);
    reference.push_back(r.quality.referenceMs);
    wait.push_back(r.waitMs);
    snr.push_back(r.quality.snrDb);
    psnr.push_back(r.quality.psnrDb);
    polygonSum += static_cast<double>(r.polygons);
    polygonsMax = std::max(polygonsMax, r.polygons);
    linkBytes += r.linkBytes;
  }
  EXPECT_EQ(s.frames, kFrames);
  expectSamePercentiles(s.renderMs, expectedPercentiles(render), "render_ms");
  expectSamePercentiles(s.poseToFrameMs, expectedPercentiles(poseToFrame), "pose_to_frame_ms");
  expectSamePercentiles(s.updateLatencyMs, expectedPercentiles(updateLatency), "update_latency_ms");
  expectSamePercentiles(s.referenceMs, expectedPercentiles(reference), "reference_ms");
  expectSamePercentiles(s.waitMs, expectedPercentiles(wait), "wait_ms");
  EXPECT_EQ(s.poseToFrameMs.count, kFrames - (kFrames + 6) / 7);
  // SNR: infinities count (every 1000th frame is +inf).
  std::sort(snr.begin(), snr.end());
  EXPECT_EQ(s.snrFrames, kFrames);
  EXPECT_EQ(s.snrMinDb, snr.front());
  EXPECT_EQ(s.snrMedianDb, snr[kFrames / 2 - 1]);
  std::sort(psnr.begin(), psnr.end());
  EXPECT_EQ(s.psnrMedianDb, psnr[kFrames / 2 - 1]);
  EXPECT_EQ(s.polygonsMax, polygonsMax);
  EXPECT_EQ(s.polygonsMean, polygonSum / kFrames);
  EXPECT_EQ(s.linkBytesTotal, linkBytes);

  // Every row is on disk, in order.
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line + "\n", frameCsvHeader());
  std::uint64_t rows = 0;
  while (std::getline(in, line)) {
    if (rows % 9973 == 0) {
      EXPECT_EQ(line + "\n", formatFrameCsvRow(syntheticFrame(rows)));
    }
    ++rows;
  }
  EXPECT_EQ(rows, kFrames);
  std::remove(path.c_str());
}

// Deferred scoring over a long run: the pending records wait on disk, not in memory.
TEST(FrameLog, ALongDeferredRunSpillsPendingRecordsInsteadOfHoldingThem) {
  constexpr std::uint64_t kFrames = 100'000;
  const std::size_t heapBefore = heapInUse();
  auto log = FrameLog::open("");
  ASSERT_TRUE(log.ok());
  for (std::uint64_t i = 0; i < kFrames; ++i) {
    FrameRecord r = syntheticFrame(i);
    r.quality = FrameQuality{};
    ASSERT_TRUE((*log)->addPending(r).ok());
  }
  const std::size_t heapPending = heapInUse();
  RecordProperty("pending_heap_bytes",
                 std::to_string(heapPending - std::min(heapBefore, heapPending)));
  EXPECT_LT(heapPending - std::min(heapBefore, heapPending), std::size_t{1} << 20)
      << "pending records held in memory";
  std::vector<FrameScore> scores;  // the kept frames: every 10th
  for (std::uint64_t i = 0; i < kFrames; i += 10) scores.push_back({i, syntheticFrame(i).quality});
  std::uint64_t next = 0;
  bool inOrderAndMerged = true;
  ASSERT_TRUE((*log)
                  ->applyScores(scores,
                                [&](const FrameRecord& r) {
                                  const bool scored = r.frame % 10 == 0;
                                  inOrderAndMerged =
                                      inOrderAndMerged && r.frame == next++ &&
                                      (scored ? r.quality.psnrDb ==
                                                    syntheticFrame(r.frame).quality.psnrDb
                                              : std::isnan(r.quality.psnrDb));
                                })
                  .ok());
  EXPECT_TRUE(inOrderAndMerged);
  EXPECT_EQ(next, kFrames);
  const ReplaySummary s = (*log)->summary().summarize();
  EXPECT_EQ(s.frames, kFrames);
  EXPECT_EQ(s.snrFrames, kFrames / 10);
}

// A scene holding what `batch` brings (uploaded and committed at once).
void hold(FrontendScene& scene, SceneBatch batch) {
  ASSERT_TRUE(scene.enqueue(std::move(batch)).ok());
  for (const PendingUpload& upload : scene.planUploads(~std::size_t{0}))
    ASSERT_TRUE(scene.markUploaded(upload.key).ok());
  scene.commitReady();
}

TEST(ObjectCsv, HeaderNamesThePerObjectColumns) {
  EXPECT_EQ(objectCsvHeader(), "frame,time_s,object,kind,triangles,vertices,skinned,posed,x,y,z\n");
}

TEST(ObjectCsv, AnEmptySceneHasNoRows) {
  EXPECT_EQ(formatObjectCsvRows(0, 0.0, FrontendScene()), "");
}

TEST(ObjectCsv, OneRowPerHeldObjectInIdOrderWithSkinAndPose) {
  using testing::addOp;
  using testing::quadMesh;
  using testing::sphereMesh;
  FrontendScene scene;
  SceneBatch batch;
  batch.plan = 1;
  const glm::mat4 at = glm::translate(glm::mat4(1.0f), glm::vec3(-3.0f, 0.0f, 0.5f));
  // Object 9: a skinned quad with its pose; object 4: a plain sphere; object 6:
  // a skinned quad whose pose has not come.
  SceneOperation skinned =
      addOp(9, RepresentationKind::kMesh, quadMesh(0, 0, 1, 1, 0), nullptr, at);
  skinned.representation.skin =
      std::make_shared<const std::vector<anim::VertexSkin>>(4, anim::VertexSkin{0, 0, 0.0f});
  SceneOperation unposed = skinned;
  unposed.id = 6;
  unposed.representation.transform = glm::mat4(1.0f);
  const std::shared_ptr<const IndexedMesh> sphere = sphereMesh(1.0f, 8, 4);
  batch.operations = {skinned, addOp(4, RepresentationKind::kMesh, sphere, nullptr), unposed};
  batch.bonePoses = {{9, BoneMatrices(1, glm::mat4(1.0f))}};
  hold(scene, std::move(batch));
  ASSERT_EQ(scene.objects().size(), 3u);
  const std::string mesh = representationKindName(RepresentationKind::kMesh);
  const std::string sphereRow = "4," + mesh + "," + std::to_string(sphere->triangleCount()) + "," +
                                std::to_string(sphere->vertexCount()) + ",0,0,0,0,0\n";
  EXPECT_EQ(formatObjectCsvRows(17, 1.7, scene), "17,1.700000," + sphereRow + "17,1.700000,6," +
                                                     mesh + ",2,4,1,0,0,0,0\n" + "17,1.700000,9," +
                                                     mesh + ",2,4,1,1,-3,0,0.5\n");
}

TEST(ObjectCsv, AnImpostorRowNamesItsKind) {
  using testing::addOp;
  using testing::solidImage;
  FrontendScene scene;
  SceneBatch batch;
  batch.operations = {
      addOp(2, RepresentationKind::kSimpleImpostor, nullptr, solidImage(2, 2, 9, 9, 9, 255))};
  hold(scene, std::move(batch));
  // Without a mesh it holds the unit quad: 2 triangles, 4 vertices.
  EXPECT_EQ(formatObjectCsvRows(0, 0.0, scene),
            std::string("0,0.000000,2,") +
                representationKindName(RepresentationKind::kSimpleImpostor) + ",2,4,0,0,0,0,0\n");
}

}  // namespace
}  // namespace thinlod::frontend
