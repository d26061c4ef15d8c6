#pragma once
// The subcommands of the `groundslam` executable. Each registers its options and its action.
#include <CLI/CLI.hpp>

namespace groundslam::apps {

void addSimulateCommand(CLI::App& app);
void addRunCommand(CLI::App& app);
void addEvaluateCommand(CLI::App& app);
void addVocabularyCommand(CLI::App& app);
void addReportCommand(CLI::App& app);
void addFloorCommand(CLI::App& app);
void addLocalizeCommand(CLI::App& app);
/// Draws RUN_DIR's figures and report.html; throws InputError when the run folder is unusable.
void writeReport(const std::string& run_dir, const std::string& compare);

}  // namespace groundslam::apps
