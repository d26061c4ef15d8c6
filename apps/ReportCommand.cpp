// `groundslam report RUN_DIR`: the paper's figures and a self-contained report.html, drawn by the
// project's matplotlib script with Debian's Python.
#include <spawn.h>
#include <sys/wait.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "Commands.hpp"
#include "groundslam/io/DataFiles.hpp"
#include "groundslam/io/InputError.hpp"

extern char** environ;

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct ReportOptions {
  std::string run_dir;
  std::string compare;
};

}  // namespace

void writeReport(const std::string& run_dir, const std::string& compare) {
  if (!fs::is_directory(run_dir)) throw InputError(run_dir + ": no such run folder");
  if (!fs::exists(GROUNDSLAM_PYTHON)) throw InputError(std::string(GROUNDSLAM_PYTHON) + ": Debian's python3 is missing (make deps)");
  std::vector<std::string> args = {GROUNDSLAM_PYTHON, dataFilePath("python/groundslam_report.py", "python/groundslam_report.py"), run_dir};
  if (!compare.empty()) args.insert(args.end(), {"--compare", compare});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();  // our lines first, then the script's
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
    throw InputError(std::string("cannot start ") + GROUNDSLAM_PYTHON);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  // The script has already named the bad file on stderr.
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw InputError("report for " + run_dir + " failed");
}

void addReportCommand(CLI::App& app) {
  auto o = std::make_shared<ReportOptions>();
  CLI::App* cmd = app.add_subcommand("report", "Draw the paper's figures and write RUN_DIR/report.html");
  cmd->add_option("RUN_DIR", o->run_dir, "Run folder written by `groundslam run`")->required();
  cmd->add_option("--compare", o->compare, "Run folder of an odometry-only run (default: RUN_DIR/odometry)");
  cmd->callback([o]() { writeReport(o->run_dir, o->compare); });
}

}  // namespace groundslam::apps
