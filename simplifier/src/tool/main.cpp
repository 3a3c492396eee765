// thinlod-simplifier: offline tool and daemon of the simplifier node. Each
// subcommand is registered by its own add*Command (commands.h).
#include <CLI/CLI.hpp>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{
      "thinlod-simplifier: progressive meshes (QEM + totally ordered mesh), accuracy curves "
      "and impostors for thinlod"};
  app.require_subcommand(1);
  thinlod::simplifier::tool::addSimplifyCommand(app);
  thinlod::simplifier::tool::addCurveCommand(app);
  thinlod::simplifier::tool::addImpostorCommand(app);
  thinlod::simplifier::tool::addServeCommand(app);
  thinlod::simplifier::tool::addPartsCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
