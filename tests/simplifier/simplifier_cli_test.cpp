// thinlod-simplifier simplify as a process: exit codes, --json on stdout,
// the mesh it writes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "thinlod/common/mesh/mesh_io.h"

namespace {

struct ProcessResult {
  int exitCode = -1;
  std::string out;  // stdout only; stderr goes to the test log
};

ProcessResult run(const std::string& arguments) {
  ProcessResult r;
  const std::string command = std::string(THINLOD_SIMPLIFIER_EXE) + " " + arguments;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  std::size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) r.out.append(buffer, n);
  const int status = pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string model(const std::string& name) {
  return std::string(THINLOD_SHARED_DIR) + "/models/" + name;
}

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("thinlod_cli_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

TEST(SimplifierCli, HelpExitsZero) {
  EXPECT_EQ(run("--help").exitCode, 0);
  EXPECT_EQ(run("simplify --help").exitCode, 0);
}

TEST(SimplifierCli, NoSubcommandFails) { EXPECT_NE(run("").exitCode, 0); }

TEST(SimplifierCli, SimplifyWritesTheRequestedTriangleCount) {
  const std::string out = tempPath("cow10.obj");
  const ProcessResult r =
      run("simplify " + model("cow.obj") + " --ratio 0.1 -o " + out + " --json");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  const nlohmann::json result = nlohmann::json::parse(r.out);
  EXPECT_TRUE(result["ok"].get<bool>());
  EXPECT_EQ(result["target_triangles"].get<int>(), 580);
  EXPECT_LE(result["output_triangles"].get<int>(), 580);
  EXPECT_GE(result["output_triangles"].get<int>(), 578);
  EXPECT_TRUE(result["timings_ms"].contains("build"));
  EXPECT_TRUE(result["timings_ms"].contains("extract"));
  auto written = thinlod::loadMeshFile(out);
  ASSERT_TRUE(written.ok()) << written.status().toString();
  EXPECT_EQ(static_cast<int>(written->mesh.triangleCount()), result["output_triangles"].get<int>());
  std::filesystem::remove(out);
}

TEST(SimplifierCli, TriangleCountOptionIsHonoured) {
  const std::string out = tempPath("teapot.ply");
  const ProcessResult r =
      run("simplify " + model("teapot.obj") + " --triangles 500 -o " + out + " --binary --json");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_LE(nlohmann::json::parse(r.out)["output_triangles"].get<int>(), 500);
  EXPECT_TRUE(std::filesystem::exists(out));
  std::filesystem::remove(out);
}

TEST(SimplifierCli, MissingInputFails) {
  EXPECT_NE(run("simplify /nonexistent/x.obj --ratio 0.5 -o " + tempPath("x.obj")).exitCode, 0);
}

TEST(SimplifierCli, RatioAndTrianglesTogetherFail) {
  EXPECT_NE(
      run("simplify " + model("cow.obj") + " --ratio 0.5 --triangles 10 -o " + tempPath("x.obj"))
          .exitCode,
      0);
}

TEST(SimplifierCli, RatioOutOfRangeFails) {
  EXPECT_NE(run("simplify " + model("cow.obj") + " --ratio 0 -o " + tempPath("x.obj")).exitCode, 0);
  EXPECT_NE(run("simplify " + model("cow.obj") + " --ratio 1.5 -o " + tempPath("x.obj")).exitCode,
            0);
}

TEST(SimplifierCli, UnknownOutputFormatFailsWithJsonError) {
  const ProcessResult r =
      run("simplify " + model("cow.obj") + " --ratio 0.5 -o " + tempPath("x.xyz") + " --json");
  EXPECT_EQ(r.exitCode, 1);
  const nlohmann::json result = nlohmann::json::parse(r.out);
  EXPECT_FALSE(result["ok"].get<bool>());
  EXPECT_EQ(result["error"]["code"], "Unsupported");
}

TEST(SimplifierCli, NanInputFailsWithJsonErrorNamingTheLine) {
  const std::string in = tempPath("nan.obj");
  {
    FILE* f = std::fopen(in.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", f);
    std::fclose(f);
  }
  const ProcessResult r =
      run("simplify " + in + " --ratio 0.5 -o " + tempPath("y.obj") + " --json");
  EXPECT_EQ(r.exitCode, 1);
  const nlohmann::json result = nlohmann::json::parse(r.out);
  EXPECT_EQ(result["error"]["code"], "InvalidArgument");
  EXPECT_NE(result["error"]["message"].get<std::string>().find(":2"), std::string::npos);
  std::filesystem::remove(in);
}

TEST(SimplifierCli, DegenerateInputFails) {
  const std::string in = tempPath("degenerate.obj");
  {
    FILE* f = std::fopen(in.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n", f);
    std::fclose(f);
  }
  const ProcessResult r =
      run("simplify " + in + " --ratio 0.5 -o " + tempPath("z.obj") + " --json");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(nlohmann::json::parse(r.out)["error"]["code"], "InvalidArgument");
  std::filesystem::remove(in);
}

}  // namespace

namespace {

TEST(SimplifierCli, CurveReportsLevelsAndCurves) {
  const std::string out = tempPath("cow_curves.json");
  const ProcessResult r =
      run("curve " + model("cow.obj") + " --levels 5 --samples 2000 --no-bytes --json -o " + out);
  ASSERT_EQ(r.exitCode, 0) << r.out;
  const nlohmann::json result = nlohmann::json::parse(r.out);
  EXPECT_TRUE(result["ok"].get<bool>());
  ASSERT_GE(result["levels"].size(), 3u);
  EXPECT_FALSE(result["triangles_curve"]["triples"].empty());
  // Coarser levels are less accurate.
  const nlohmann::json& levels = result["levels"];
  EXPECT_GT(levels.front()["relative_max_error"].get<double>(),
            levels.back()["relative_max_error"].get<double>());
  EXPECT_TRUE(std::filesystem::exists(out));
  std::filesystem::remove(out);
}

TEST(SimplifierCli, CurveOfMissingFileFails) {
  EXPECT_NE(run("curve /nonexistent/x.obj --json").exitCode, 0);
}

}  // namespace
