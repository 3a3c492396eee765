// Frame records: CSV formatting, percentiles, summary and its JSON, file wrappers.
#include "thinlod/frontend/frame_record.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

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
  r.snrDb = 11.25;
  r.psnrDb = 30.5;
  r.renderMs = 2.6;
  r.poseToFrameMs = 7.125;
  r.updateLatencyMs = 31.5;
  r.plan = 3;
  r.drawCalls = 2;
  r.uploadedBytes = 524288;
  return r;
}

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "thinlod_frontend_" + std::to_string(::getpid()) + "_" + name;
}

TEST(FrameRecord, HeaderHasTheRequiredColumnsInOrder) {
  EXPECT_EQ(frameCsvHeader(),
            "frame,time_s,polygons,link_bytes,target_accuracy,snr_db,psnr_db,render_ms,"
            "pose_to_frame_ms,update_latency_ms,plan,draw_calls,uploaded_bytes\n");
}

TEST(FrameRecord, RowFormatsEveryColumn) {
  EXPECT_EQ(formatFrameCsvRow(sampleRecord()),
            "12,0.400000,348,262144,200,11.2500,30.5000,2.6000,7.1250,31.5000,3,2,524288\n");
}

TEST(FrameRecord, MissingValuesAreEmptyAndInfinitiesSpelledOut) {
  FrameRecord r;
  r.frame = 1;
  r.snrDb = kInf;
  r.psnrDb = kInf;
  EXPECT_EQ(formatFrameCsvRow(r), "1,0.000000,0,0,,inf,inf,,,,0,0,0\n");
  r.snrDb = -kInf;
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

TEST(FrameRecord, SummaryCountsSnrWithInfinities) {
  std::vector<FrameRecord> records(5, sampleRecord());
  records[0].snrDb = 8.0;
  records[1].snrDb = kInf;
  records[2].snrDb = 12.0;
  records[3].snrDb = FrameRecord::kMissing;  // not measured
  records[4].snrDb = 0.0;
  records[4].polygons = 400;
  records[2].renderMs = 9.0;
  const ReplaySummary s = summarizeFrames(records);
  EXPECT_EQ(s.frames, 5u);
  EXPECT_EQ(s.snrFrames, 4u);
  EXPECT_EQ(s.snrMinDb, 0.0);
  EXPECT_EQ(s.snrMedianDb, 8.0);  // sorted {0, 8, 12, inf}: element ceil(2) - 1
  EXPECT_EQ(s.renderMs.median, 2.6);
  EXPECT_EQ(s.renderMs.max, 9.0);
  EXPECT_EQ(s.polygonsMax, 400u);
  EXPECT_DOUBLE_EQ(s.polygonsMean, (4 * 348.0 + 400.0) / 5.0);
  EXPECT_EQ(s.linkBytesTotal, 5u * 262144u);
}

TEST(FrameRecord, EmptySummaryHasNoValues) {
  const ReplaySummary s = summarizeFrames({});
  EXPECT_EQ(s.frames, 0u);
  EXPECT_TRUE(std::isnan(s.snrMedianDb));
  EXPECT_TRUE(std::isnan(s.polygonsMean));
}

TEST(FrameRecord, SummaryJsonRoundTrips) {
  std::vector<FrameRecord> records(3, sampleRecord());
  records[1].snrDb = kInf;
  records[2].poseToFrameMs = FrameRecord::kMissing;
  records[0].updateLatencyMs = 12.0;
  records[1].updateLatencyMs = FrameRecord::kMissing;
  const nlohmann::json json = nlohmann::json::parse(summaryJson(summarizeFrames(records)));
  EXPECT_EQ(json["frames"], 3);
  EXPECT_EQ(json["render_ms"]["median"], 2.6);
  EXPECT_EQ(json["render_ms"]["p99"], 2.6);
  EXPECT_EQ(json["pose_to_frame_ms"]["count"], 2);
  EXPECT_EQ(json["update_latency_ms"]["count"], 2);
  EXPECT_EQ(json["update_latency_ms"]["median"], 12.0);
  EXPECT_EQ(json["update_latency_ms"]["max"], 31.5);
  EXPECT_EQ(json["snr_db"]["median"], 11.25);
  EXPECT_EQ(json["snr_db"]["min"], 11.25);
  EXPECT_EQ(json["snr_db"]["count"], 3);
  EXPECT_EQ(json["link_bytes_total"], 3 * 262144);
}

TEST(FrameRecord, SummaryJsonSpellsInfinityAndNull) {
  std::vector<FrameRecord> records(1, sampleRecord());
  records[0].snrDb = kInf;
  records[0].psnrDb = kInf;
  records[0].poseToFrameMs = FrameRecord::kMissing;
  const nlohmann::json json = nlohmann::json::parse(summaryJson(summarizeFrames(records)));
  EXPECT_EQ(json["snr_db"]["median"], "inf");
  EXPECT_EQ(json["psnr_db"]["median"], "inf");
  EXPECT_TRUE(json["pose_to_frame_ms"]["median"].is_null());
}

TEST(FrameRecord, CsvWriterWritesHeaderAndRows) {
  const std::string path = tempPath("frames.csv");
  {
    auto writer = FrameCsvWriter::open(path);
    ASSERT_TRUE(writer.ok()) << writer.status().toString();
    ASSERT_TRUE((*writer)->append(sampleRecord()).ok());
    FrameRecord second = sampleRecord();
    second.frame = 13;
    ASSERT_TRUE((*writer)->append(second).ok());
    ASSERT_TRUE((*writer)->close().ok());
    EXPECT_EQ((*writer)->append(second).code(), ErrorCode::kIoError);  // closed
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  FrameRecord second = sampleRecord();
  second.frame = 13;
  EXPECT_EQ(text.str(),
            frameCsvHeader() + formatFrameCsvRow(sampleRecord()) + formatFrameCsvRow(second));
  std::remove(path.c_str());
}

TEST(FrameRecord, CsvWriterReportsAnUnwritablePath) {
  auto writer = FrameCsvWriter::open("/nonexistent-dir/frames.csv");
  ASSERT_FALSE(writer.ok());
  EXPECT_EQ(writer.status().code(), ErrorCode::kIoError);
  EXPECT_NE(writer.status().message().find("/nonexistent-dir/frames.csv"), std::string::npos);
}

TEST(FrameRecord, SummaryFileMatchesSummaryJson) {
  const std::string path = tempPath("summary.json");
  const ReplaySummary summary = summarizeFrames({sampleRecord()});
  ASSERT_TRUE(writeSummaryJson(path, summary).ok());
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), summaryJson(summary) + "\n");
  std::remove(path.c_str());
  EXPECT_EQ(writeSummaryJson("/nonexistent-dir/s.json", summary).code(), ErrorCode::kIoError);
}

}  // namespace
}  // namespace thinlod::frontend
