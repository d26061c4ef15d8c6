#pragma once
// The subcommands of the `groundslam` executable. Each registers its options and its action.
#include <CLI/CLI.hpp>

namespace groundslam::apps {

void addSimulateCommand(CLI::App& app);
void addRunCommand(CLI::App& app);
void addEvaluateCommand(CLI::App& app);
void addVocabularyCommand(CLI::App& app);

}  // namespace groundslam::apps
