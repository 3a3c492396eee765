// Subcommands of the thinlod-simplifier executable. One file per subcommand,
// each exposing add<Name>Command(CLI::App&), which registers the subcommand,
// its options and its callback on the root app; main.cpp calls every one.
// To add a subcommand: write <name>_command.cpp, declare it here, call it in
// main.cpp.
//
// Conventions for every subcommand:
// - `--help` works (CLI11); progress and human messages go to stderr; with
//   `--json` the one machine-readable result object goes to stdout.
// - Failures print a clear message naming the file/option and end the
//   process with a non-zero exit code by throwing CLI::RuntimeError(code)
//   (see tool_output.h); CLI11 turns it into the return value of main.
#pragma once

namespace CLI {
class App;
}

namespace thinlod::simplifier::tool {

void addSimplifyCommand(CLI::App& app);  // simplify IN (--ratio R | --triangles N) -o OUT
void addCurveCommand(CLI::App& app);     // curve IN [-o CURVES.json]: measured accuracy curves
void addImpostorCommand(CLI::App& app);  // impostor IN [--meshed] [--size N]: render one impostor
void addServeCommand(CLI::App& app);     // serve: the simplifier daemon (serve_command.cpp)
void addPartsCommand(CLI::App& app);     // parts -o OUT: the generated multi-manifold model

}  // namespace thinlod::simplifier::tool
