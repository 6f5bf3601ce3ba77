#pragma once

#include <CLI/CLI.hpp>

// Each subcommand lives in its own cmd_<name>.cc and registers itself on the top-level app.
// A command's action throws noctua::Error for bad input; main() turns it into a one-line reason
// and a non-zero exit code.
namespace noctua::app {

// Each Add*Command adds one subcommand (with its --help) and binds its action.
// Keep this list in the order of `noctua --help`.
void AddDemoCommand(CLI::App& app);
void AddExtractCommand(CLI::App& app);
void AddEdgesCommand(CLI::App& app);
void AddDetectCommand(CLI::App& app);
void AddAteCommand(CLI::App& app);
void AddRpeCommand(CLI::App& app);
void AddSlamCommand(CLI::App& app);
void AddVocabCommand(CLI::App& app);
void AddSimulateCommand(CLI::App& app);
void AddEvalCommand(CLI::App& app);
void AddBenchCommand(CLI::App& app);

}  // namespace noctua::app
