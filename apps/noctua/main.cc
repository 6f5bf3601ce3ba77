#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.h"
#include "noctua/util/allocator.h"
#include "noctua/util/error.h"
#include "noctua/util/version.h"

int main(int argc, char** argv) {
  // Frame buffers stay in the process: without it every large image of every frame is faulted in
  // anew, and a stage's speed depended on which models happened to be loaded.
  noctua::util::KeepFrameBuffersInProcess();
  CLI::App app{"noctua: feature points for visual SLAM that survive low light and moving people"};
  app.require_subcommand(1);
  app.set_version_flag("--version", noctua::Version());
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Log debugging detail");
  app.parse_complete_callback(
      [&] { spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info); });
  spdlog::set_pattern("[%l] %v");
  // Subcommands (one Add*Command per cmd_<name>.cc, declared in commands.h):
  noctua::app::AddDemoCommand(app);
  noctua::app::AddExtractCommand(app);
  noctua::app::AddEdgesCommand(app);
  noctua::app::AddDetectCommand(app);
  noctua::app::AddAteCommand(app);
  noctua::app::AddRpeCommand(app);
  noctua::app::AddSlamCommand(app);
  noctua::app::AddVocabCommand(app);
  noctua::app::AddSimulateCommand(app);
  noctua::app::AddEvalCommand(app);
  noctua::app::AddBenchCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  } catch (const noctua::Error& error) {
    std::cerr << "noctua: error: " << error.what() << "\n";
    return 1;
  } catch (const std::exception& error) {
    std::cerr << "noctua: internal error: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
