// thinlod-frontend as a real process against an in-test backbone Endpoint on
// loopback (integration tier): lockstep replay of the paper room, no
// backbone at all, and SIGTERM in the middle of a replay.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "daemon_test_util.h"
#include "thinlod/common/core/frame_cost.h"
#include "thinlod/common/core/trace.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::frontend::daemon {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

// Generous: a loaded 2-core machine must never fail these tests by being slow.
constexpr auto kProcessDeadline = 90s;

const std::string kScene = std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl";
const std::string kModels = std::string(THINLOD_SHARED_DIR) + "/models";

std::string makeTempDir() {
  std::string pattern = ::testing::TempDir() + "thinlod_frontend_daemon_XXXXXX";
  char* made = mkdtemp(pattern.data());
  EXPECT_NE(made, nullptr);
  return pattern;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::string field;
  std::stringstream stream(line);
  while (std::getline(stream, field, separator)) fields.push_back(field);
  if (!line.empty() && line.back() == separator) fields.emplace_back();
  return fields;
}

// Rows of a CSV as column name -> field.
std::vector<std::map<std::string, std::string>> readCsv(const std::string& path,
                                                        std::vector<std::string>* header) {
  std::vector<std::map<std::string, std::string>> rows;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return rows;
  *header = split(line, ',');
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = split(line, ',');
    EXPECT_EQ(fields.size(), header->size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < fields.size() && i < header->size(); ++i) {
      row[(*header)[i]] = fields[i];
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

double numberOf(const std::string& field) {
  if (field.empty()) return std::nan("");
  if (field == "inf") return INFINITY;
  if (field == "-inf") return -INFINITY;
  return std::stod(field);
}

// Five poses from the room's open end looking in, 50 ms apart.
std::string writeTrace(const std::string& dir, int poses, double spacingS) {
  Trace trace;
  for (int i = 0; i < poses; ++i) {
    Pose pose;
    pose.time = i * spacingS;
    pose.position = glm::vec3(2.0f + 0.02f * static_cast<float>(i % 10), 1.5f, 4.8f);
    pose.orientation = lookAtOrientation(pose.position, glm::vec3(2.0f, 0.4f, 1.6f));
    pose.fovYDegrees = 60.0f;
    trace.poses.push_back(pose);
  }
  const std::string path = dir + "/flight.trace";
  EXPECT_TRUE(saveTraceFile(path, trace).ok());
  return path;
}

class FrontendProcess {
 public:
  FrontendProcess(const std::vector<std::string>& args, const std::string& logPath) {
    pid_ = fork();
    if (pid_ == 0) {
      const int log = ::open(logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (log >= 0) {
        dup2(log, STDERR_FILENO);
        dup2(log, STDOUT_FILENO);
      }
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(THINLOD_FRONTEND_EXE));
      for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
      argv.push_back(nullptr);
      execv(THINLOD_FRONTEND_EXE, argv.data());
      _exit(127);
    }
  }
  ~FrontendProcess() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  // Calls step() until the process exits; its exit code, or -1 at the deadline.
  int waitExit(const std::function<void()>& step) {
    const auto end = std::chrono::steady_clock::now() + kProcessDeadline;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      step();
    }
    return -1;
  }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
};

// The scene as the backbone numbers it.
struct RoomScene {
  scene::Scene scene;
  std::vector<scene::SceneObject> objects;
};

std::unique_ptr<RoomScene> loadRoom() {
  scene::SceneLoadOptions options;
  options.meshSearchPaths = {kModels};
  auto loaded = scene::loadSceneFile(kScene, options);
  EXPECT_TRUE(loaded.ok()) << loaded.status().toString();
  if (!loaded.ok()) return nullptr;
  auto room = std::make_unique<RoomScene>();
  room->scene = std::move(loaded).value();
  auto objects = scene::collectSceneObjects(room->scene);
  EXPECT_TRUE(objects.ok()) << objects.status().toString();
  if (objects.ok()) room->objects = std::move(objects).value();
  return room;
}

protocol::Representation fullMeshOf(const scene::SceneObject& object) {
  return testing::meshRepresentation(*object.fullMesh, object.objectToWorld);
}

TEST(FrontendProcess, LockstepReplayOfThePaperRoomAgainstAFakeBackbone) {
  const std::unique_ptr<RoomScene> room = loadRoom();
  ASSERT_NE(room, nullptr);
  ASSERT_EQ(room->objects.size(), 4u);  // two spheres, the column, the cow

  protocol::Endpoint::Options endpointOptions;
  endpointOptions.address = "tcp://127.0.0.1:0";
  endpointOptions.name = "fake-backbone";
  endpointOptions.acceptedRoles = {protocol::Role::kFrontend};
  auto endpoint = protocol::Endpoint::bind(endpointOptions);
  ASSERT_TRUE(endpoint.ok()) << endpoint.status().toString();

  // The answers, one per pose (plan = pose + 1, target = 10 * plan):
  //   0: nothing; 1: object 1 as a 24x12 UV sphere; 2: objects 2, 3, 4 at full
  //   resolution; 3: a valid replacement of 1 plus corrupted Draco bytes for
  //   2 (the whole update must be dropped); 4: nothing.
  const IndexedMesh lowSphere = testing::sphereMesh(0.3f, 24, 12);
  std::vector<protocol::SceneUpdate> answers(5);
  for (std::uint64_t i = 0; i < answers.size(); ++i) {
    answers[i].plan = i + 1;
    answers[i].frame = i;
    answers[i].targetAccuracy = 10.0 * (i + 1);
  }
  answers[1].operations.push_back(
      testing::addOp(1, testing::meshRepresentation(lowSphere, room->objects[0].objectToWorld)));
  for (std::size_t k = 1; k < 4; ++k) {
    answers[2].operations.push_back(
        testing::addOp(room->objects[k].id, fullMeshOf(room->objects[k])));
  }
  answers[3].operations.push_back(testing::addOp(1, fullMeshOf(room->objects[0])));
  protocol::Representation broken = fullMeshOf(room->objects[1]);
  broken.mesh.resize(broken.mesh.size() - 100);
  answers[3].operations.push_back(testing::addOp(2, broken));
  std::size_t fullTriangles = 0;
  for (std::size_t k = 1; k < 4; ++k) fullTriangles += room->objects[k].fullMesh->triangleCount();

  const std::string dir = makeTempDir();
  const std::string csv = dir + "/frames.csv";
  const std::string summary = dir + "/summary.json";
  const std::string framesDir = dir + "/frames";
  FrontendProcess process({"--backbone.address",
                           (*endpoint)->address(),
                           "--scene",
                           kScene,
                           "--models-dir",
                           kModels,
                           "--trace",
                           writeTrace(dir, 5, 0.05),
                           "--lockstep",
                           "--lockstep-timeout-ms",
                           "20000",
                           "--csv",
                           csv,
                           "--summary-json",
                           summary,
                           "--frames-dir",
                           framesDir,
                           "--dump-every",
                           "2",
                           "--label",
                           "integration",
                           "--width",
                           "320",
                           "--height",
                           "240"},
                          dir + "/frontend.log");

  std::vector<protocol::FrameStats> stats;
  std::vector<std::uint64_t> poses;
  const int exitCode = process.waitExit([&] {
    for (auto& event : (*endpoint)->poll(20ms)) {
      if (event.kind != protocol::EndpointEvent::Kind::kMessage) continue;
      if (const auto* pose = std::get_if<protocol::ViewerPose>(&event.message)) {
        poses.push_back(pose->sequence);
        ASSERT_LT(pose->sequence, answers.size());
        EXPECT_EQ(pose->viewportWidth, 320u);
        EXPECT_TRUE((*endpoint)->send(event.peer, answers[pose->sequence]).ok());
      } else if (const auto* frame = std::get_if<protocol::FrameStats>(&event.message)) {
        stats.push_back(*frame);
      }
    }
  });
  const std::string log = readFile(dir + "/frontend.log");
  ASSERT_EQ(exitCode, 0) << log;
  EXPECT_NE(log.find("event=ready"), std::string::npos) << log;
  EXPECT_NE(log.find("event=update_rejected plan=4"), std::string::npos) << log;

  std::vector<std::string> header;
  const auto rows = readCsv(csv, &header);
  const std::vector<std::string> required = {"frame",      "time_s",          "polygons",
                                             "link_bytes", "target_accuracy", "snr_db",
                                             "psnr_db",    "render_ms",       "pose_to_frame_ms"};
  ASSERT_GE(header.size(), required.size());
  EXPECT_EQ(std::vector<std::string>(header.begin(), header.begin() + required.size()), required);
  ASSERT_EQ(rows.size(), 5u) << readFile(csv);
  EXPECT_EQ(poses, (std::vector<std::uint64_t>{0, 1, 2, 3, 4}));

  std::vector<double> snr;
  std::vector<std::size_t> polygons;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    SCOPED_TRACE(i);
    const auto& row = rows[i];
    EXPECT_EQ(row.at("frame"), std::to_string(i));
    EXPECT_NEAR(numberOf(row.at("time_s")), 0.05 * i, 1e-9);
    polygons.push_back(static_cast<std::size_t>(numberOf(row.at("polygons"))));
    snr.push_back(numberOf(row.at("snr_db")));
    EXPECT_TRUE(std::isfinite(numberOf(row.at("render_ms"))));
    EXPECT_TRUE(std::isfinite(numberOf(row.at("psnr_db"))));
    EXPECT_EQ(row.at("lockstep_timeout"), "0");
    // Frame 3's update was rejected: nothing new became visible.
    EXPECT_EQ(std::isfinite(numberOf(row.at("update_latency_ms"))), i != 3);
    // Every frame has its own latency; in lockstep it covers the wait, so it is at least
    // the render time.
    EXPECT_GE(numberOf(row.at("pose_to_frame_ms")), numberOf(row.at("render_ms")));
    const double expectedTarget = 10.0 * (i == 3 ? 3 : i + 1);
    EXPECT_DOUBLE_EQ(numberOf(row.at("target_accuracy")), expectedTarget);
  }
  EXPECT_EQ(polygons[0], 0u);
  EXPECT_EQ(polygons[1], lowSphere.triangleCount());
  EXPECT_EQ(polygons[2], lowSphere.triangleCount() + fullTriangles);
  EXPECT_EQ(polygons[3], polygons[2]);  // nothing half applied
  EXPECT_EQ(polygons[4], polygons[2]);
  for (std::size_t i = 1; i < 5; ++i) EXPECT_TRUE(std::isfinite(snr[i])) << i << ": " << snr[i];
  // Every object at (Draco-quantised) full resolution matches the reference
  // far better than one sphere alone.
  EXPECT_GT(snr[2], snr[1] + 3.0);
  EXPECT_GT(snr[2], 15.0);
  EXPECT_GT(numberOf(rows[1].at("link_bytes")), 1000.0);
  EXPECT_GT(numberOf(rows[2].at("link_bytes")), numberOf(rows[1].at("link_bytes")));

  // The backbone heard every frame (the last FrameStats may race the exit).
  ASSERT_GE(stats.size(), 4u);
  for (std::size_t i = 0; i < stats.size(); ++i) {
    EXPECT_EQ(stats[i].frame, i);
    EXPECT_EQ(stats[i].polygons, polygons[i]);
    EXPECT_EQ(stats[i].hasSnr, std::isfinite(snr[i]));
  }

  const nlohmann::json json = nlohmann::json::parse(readFile(summary));
  EXPECT_EQ(json["frames"], 5);
  EXPECT_EQ(json["label"], "integration");
  EXPECT_EQ(json["polygons"]["max"], polygons[2]);
  EXPECT_EQ(json["updates"]["received"], 5);
  EXPECT_EQ(json["updates"]["rejected"], 1);
  EXPECT_EQ(json["interrupted"], false);
  for (const char* name : {"frame_0000.png", "reference_0000.png", "frame_0002.png",
                           "reference_0002.png", "frame_0004.png"}) {
    EXPECT_TRUE(fs::exists(framesDir + "/" + name)) << name;
  }
  EXPECT_FALSE(fs::exists(framesDir + "/frame_0001.png"));

  // Per-frame timings, printed for the record.
  for (const auto& row : rows) {
    std::printf(
        "frame %s: polygons %s snr_db %s render_ms %s reference_ms %s pose_to_frame_ms %s\n",
        row.at("frame").c_str(), row.at("polygons").c_str(), row.at("snr_db").c_str(),
        row.at("render_ms").c_str(), row.at("reference_ms").c_str(),
        row.at("pose_to_frame_ms").c_str());
  }
  fs::remove_all(dir);
}

TEST(FrontendProcess, WithoutABackboneItStillRendersEveryFrameAndExitsZero) {
  // A port that was free a moment ago: nothing answers there.
  std::string address;
  {
    protocol::Endpoint::Options options;
    options.address = "tcp://127.0.0.1:0";
    auto endpoint = protocol::Endpoint::bind(options);
    ASSERT_TRUE(endpoint.ok());
    address = (*endpoint)->address();
  }
  const std::string dir = makeTempDir();
  const std::string csv = dir + "/frames.csv";
  FrontendProcess process({"--backbone.address", address, "--trace", writeTrace(dir, 5, 0.02),
                           "--no-reference", "--lockstep", "--connect-timeout-ms", "200", "--csv",
                           csv, "--width", "160", "--height", "120"},
                          dir + "/frontend.log");
  const int exitCode = process.waitExit([] { std::this_thread::sleep_for(10ms); });
  const std::string log = readFile(dir + "/frontend.log");
  ASSERT_EQ(exitCode, 0) << log;
  EXPECT_NE(log.find("event=backbone_unavailable"), std::string::npos) << log;
  EXPECT_NE(log.find("event=ready"), std::string::npos) << log;
  std::vector<std::string> header;
  const auto rows = readCsv(csv, &header);
  ASSERT_EQ(rows.size(), 5u);
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("polygons"), "0");
    EXPECT_EQ(row.at("snr_db"), "");  // not measured
    EXPECT_EQ(row.at("lockstep_timeout"), "0");
  }
  fs::remove_all(dir);
}

TEST(FrontendProcess, DeferredReferenceScoresEveryShownFrameLikeTheInlineReference) {
  // No backbone: every frame is empty, so each shown frame is blank against its
  // reference. The deferred run (references after the replay) must give the same
  // per-frame SNR, completeness and reference images as the inline run.
  const std::string dir = makeTempDir();
  const std::string trace = writeTrace(dir, 5, 0.02);
  struct Run {
    std::vector<std::map<std::string, std::string>> rows;
    std::string summary;
  };
  const auto run = [&](const std::string& name, bool deferred) {
    const std::string out = dir + "/" + name;
    fs::create_directories(out);
    std::vector<std::string> args = {"--backbone.address",
                                     "tcp://127.0.0.1:1",
                                     "--trace",
                                     trace,
                                     "--scene",
                                     kScene,
                                     "--models-dir",
                                     kModels,
                                     "--connect-timeout-ms",
                                     "0",
                                     "--csv",
                                     out + "/frames.csv",
                                     "--summary-json",
                                     out + "/summary.json",
                                     "--frames-dir",
                                     out + "/frames",
                                     "--dump-every",
                                     "2",
                                     "--width",
                                     "160",
                                     "--height",
                                     "120"};
    args.push_back("--completeness");
    if (deferred) args.push_back("--deferred-reference");
    FrontendProcess process(args, out + "/frontend.log");
    const int exitCode = process.waitExit([] { std::this_thread::sleep_for(10ms); });
    EXPECT_EQ(exitCode, 0) << readFile(out + "/frontend.log");
    Run result;
    std::vector<std::string> header;
    result.rows = readCsv(out + "/frames.csv", &header);
    result.summary = readFile(out + "/summary.json");
    return result;
  };
  const Run inlineRun = run("inline", false);
  const Run deferredRun = run("deferred", true);
  ASSERT_EQ(inlineRun.rows.size(), 5u);
  ASSERT_EQ(deferredRun.rows.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    const auto& a = inlineRun.rows[i];
    const auto& b = deferredRun.rows[i];
    EXPECT_EQ(b.at("frame"), std::to_string(i));
    EXPECT_EQ(b.at("snr_db"), "-inf");  // an empty frame against a non-empty reference
    EXPECT_EQ(b.at("blank"), "1");
    EXPECT_GE(numberOf(b.at("visible_objects")), 1.0);
    EXPECT_EQ(b.at("missing_objects"), b.at("visible_objects"));  // nothing held
    for (const char* column :
         {"snr_db", "psnr_db", "visible_objects", "missing_objects", "blank"}) {
      EXPECT_EQ(a.at(column), b.at(column)) << column << " of frame " << i;
    }
    EXPECT_FALSE(b.at("shown_at_ms").empty());
  }
  EXPECT_NE(inlineRun.summary.find("\"reference_mode\": \"inline\""), std::string::npos);
  EXPECT_NE(deferredRun.summary.find("\"reference_mode\": \"deferred\""), std::string::npos)
      << deferredRun.summary;
  for (const char* kind : {"frame", "reference", "difference"}) {
    for (int frame : {0, 2, 4}) {
      char name[64];
      std::snprintf(name, sizeof(name), "/%s_%04d.png", kind, frame);
      const std::string deferredPng = readFile(dir + "/deferred/frames" + name);
      EXPECT_FALSE(deferredPng.empty()) << name;
      EXPECT_EQ(deferredPng, readFile(dir + "/inline/frames" + name)) << name;  // byte-identical
    }
  }
  fs::remove_all(dir);
}

TEST(FrontendProcess, SigtermEndsTheReplayEarlyAndStillWritesTheOutputs) {
  const std::string dir = makeTempDir();
  const std::string csv = dir + "/frames.csv";
  const std::string summary = dir + "/summary.json";
  // 60 poses one second apart: far longer than the test waits.
  FrontendProcess process(
      {"--backbone.address", "tcp://127.0.0.1:1", "--trace", writeTrace(dir, 60, 1.0),
       "--no-reference", "--connect-timeout-ms", "0", "--csv", csv, "--summary-json", summary,
       "--width", "160", "--height", "120"},
      dir + "/frontend.log");
  // Wait for the first row, then signal.
  const auto end = std::chrono::steady_clock::now() + kProcessDeadline;
  std::vector<std::string> header;
  while (std::chrono::steady_clock::now() < end && readCsv(csv, &header).empty()) {
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_FALSE(readCsv(csv, &header).empty()) << readFile(dir + "/frontend.log");
  kill(process.pid(), SIGTERM);
  const int exitCode = process.waitExit([] { std::this_thread::sleep_for(10ms); });
  ASSERT_EQ(exitCode, 0) << readFile(dir + "/frontend.log");
  const auto rows = readCsv(csv, &header);
  EXPECT_GE(rows.size(), 1u);
  EXPECT_LT(rows.size(), 60u);
  const nlohmann::json json = nlohmann::json::parse(readFile(summary));
  EXPECT_EQ(json["interrupted"], true);
  EXPECT_EQ(json["frames"], rows.size());
  fs::remove_all(dir);
}

TEST(FrontendProcess, FollowsALivePoseStreamFromAFifoSkippingABadLine) {
  const std::string dir = makeTempDir();
  const std::string fifo = dir + "/poses";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string csv = dir + "/frames.csv";
  const std::string summary = dir + "/summary.json";
  // Rate 0: one frame per arriving pose.
  FrontendProcess process({"--backbone.address", "tcp://127.0.0.1:1", "--pose-stream", fifo,
                           "--no-reference", "--connect-timeout-ms", "0", "--csv", csv,
                           "--summary-json", summary, "--width", "160", "--height", "120"},
                          dir + "/frontend.log");
  const int writer = ::open(fifo.c_str(), O_WRONLY);  // blocks until the frontend opened it
  ASSERT_GE(writer, 0);
  auto send = [&](const std::string& text) {
    ASSERT_EQ(::write(writer, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  };
  // Each pose is written once the previous one has its CSV row, so no pose
  // overtakes another however slow the machine is.
  auto waitForRows = [&](std::size_t rows) {
    std::vector<std::string> ignored;
    const auto end = std::chrono::steady_clock::now() + kProcessDeadline;
    while (std::chrono::steady_clock::now() < end && readCsv(csv, &ignored).size() < rows) {
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_EQ(readCsv(csv, &ignored).size(), rows) << readFile(dir + "/frontend.log");
  };
  send("# thinlod-trace 1\n0.0 2 1.5 4.8 lookat 2 0.4 1.6 60\n");
  waitForRows(1);
  send("0.1 2 1.5 4.7 lookat 2 0.4 1.6 60\n");
  waitForRows(2);
  send("0.2 2 1.5 nan lookat 2 0.4 1.6 60\n");  // line 4: rejected, skipped
  send("0.3 2 1.5 4.6 look");                   // a pose in two writes
  std::this_thread::sleep_for(50ms);
  send("at 2 0.4 1.6 60\n");
  waitForRows(3);
  ::close(writer);  // end of stream: the frontend finishes
  const int exitCode = process.waitExit([] { std::this_thread::sleep_for(10ms); });
  const std::string log = readFile(dir + "/frontend.log");
  ASSERT_EQ(exitCode, 0) << log;
  EXPECT_NE(log.find("event=pose_rejected action=skipped error=\"ParseError: line 4:"),
            std::string::npos)
      << log;
  std::vector<std::string> header;
  const auto rows = readCsv(csv, &header);
  ASSERT_EQ(rows.size(), 3u) << readFile(csv);
  const double times[] = {0.0, 0.1, 0.3};
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_NEAR(numberOf(rows[i].at("time_s")), times[i], 1e-9);
    EXPECT_TRUE(std::isfinite(numberOf(rows[i].at("pose_to_frame_ms"))));
  }
  const nlohmann::json json = nlohmann::json::parse(readFile(summary));
  EXPECT_EQ(json["pose_stream"], fifo);
  EXPECT_EQ(json["pose_stream_received"], 3);
  EXPECT_EQ(json["pose_stream_lines_rejected"], 1);
  EXPECT_EQ(json["poses_skipped"], 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace thinlod::frontend::daemon

namespace thinlod::frontend::daemon {
namespace {

// --frame-cost FILE: the constants reach the backbone in the Hello, bit for
// bit as bench_calibrate wrote them.
TEST(FrontendProcess, SendsItsFrameCostConstantsInTheHello) {
  protocol::Endpoint::Options endpointOptions;
  endpointOptions.address = "tcp://127.0.0.1:0";
  endpointOptions.name = "fake-backbone";
  endpointOptions.acceptedRoles = {protocol::Role::kFrontend};
  std::optional<protocol::Hello> seen;
  endpointOptions.admit = [&seen](const protocol::Hello& hello) {
    seen = hello;
    return Status();
  };
  auto endpoint = protocol::Endpoint::bind(endpointOptions);
  ASSERT_TRUE(endpoint.ok()) << endpoint.status().toString();
  const std::string dir = makeTempDir();
  FrameCostConstants costs;
  costs.initSeconds = 3.1e-4;
  costs.finalSeconds = 2.7e-4;
  costs.setupSeconds = 1.25e-5;
  costs.triangleSeconds = 1.48e-7;
  costs.pixelSeconds = 6.8e-8;
  costs.additive = true;
  const std::string costFile = dir + "/frame_cost.toml";
  std::ofstream(costFile) << formatFrameCostToml(costs, "test machine");
  FrontendProcess process(
      {"--backbone.address", (*endpoint)->address(), "--trace", writeTrace(dir, 3, 0.02),
       "--no-reference", "--frame-cost", costFile, "--width", "160", "--height", "120"},
      dir + "/frontend.log");
  const int exitCode = process.waitExit([&] {
    for (auto& event : (*endpoint)->poll(20ms)) {
      if (event.kind != protocol::EndpointEvent::Kind::kMessage) continue;
      if (const auto* pose = std::get_if<protocol::ViewerPose>(&event.message)) {
        protocol::SceneUpdate empty;
        empty.frame = pose->sequence;
        (void)(*endpoint)->send(event.peer, empty);
      }
    }
  });
  const std::string log = readFile(dir + "/frontend.log");
  ASSERT_EQ(exitCode, 0) << log;
  ASSERT_TRUE(seen.has_value()) << log;
  ASSERT_TRUE(seen->frameCost.has_value());
  EXPECT_EQ(seen->frameCost->initSeconds, costs.initSeconds);
  EXPECT_EQ(seen->frameCost->finalSeconds, costs.finalSeconds);
  EXPECT_EQ(seen->frameCost->setupSeconds, costs.setupSeconds);
  EXPECT_EQ(seen->frameCost->triangleSeconds, costs.triangleSeconds);
  EXPECT_EQ(seen->frameCost->pixelSeconds, costs.pixelSeconds);
  EXPECT_TRUE(seen->frameCost->additive);
  fs::remove_all(dir);
}

TEST(FrontendProcess, RefusesAnUnusableFrameCostFileBeforeConnecting) {
  const std::string dir = makeTempDir();
  FrameCostConstants free;
  free.pixelSeconds = 1e-8;  // triangles cost nothing: no use for a frame-time budget
  const std::string freeFile = dir + "/free.toml";
  std::ofstream(freeFile) << formatFrameCostToml(free, "");
  const std::string nanFile = dir + "/nan.toml";
  std::ofstream(nanFile) << "version = 1\ninit_seconds = 0\nfinal_seconds = 0\n"
                            "setup_seconds = 0\ntriangle_seconds = nan\npixel_seconds = 0\n"
                            "additive = 0\n";
  struct Case {
    std::string file;
    const char* expected;
  };
  for (const Case& c : {Case{freeFile, "must be > 0"}, Case{nanFile, "must be finite"},
                        Case{dir + "/missing.toml", "cannot open"}}) {
    FrontendProcess process({"--backbone.address", "tcp://127.0.0.1:1", "--trace",
                             writeTrace(dir, 2, 0.02), "--no-reference", "--frame-cost", c.file},
                            dir + "/frontend.log");
    const int exitCode = process.waitExit([] { std::this_thread::sleep_for(10ms); });
    const std::string log = readFile(dir + "/frontend.log");
    EXPECT_EQ(exitCode, 2) << log;
    EXPECT_NE(log.find("--frame-cost"), std::string::npos) << log;
    EXPECT_NE(log.find(c.file), std::string::npos) << log;
    EXPECT_NE(log.find(c.expected), std::string::npos) << log;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace thinlod::frontend::daemon
