// Issue 14, "nothing lost": result files are replaced atomically, a run folder is not overwritten
// without --force, and Ctrl-C leaves a consistent folder marked interrupted.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "ifab/core/testing/error_of.h"
#include "ifab/experiments/atomic_file.h"
#include "ifab/experiments/experiment.h"

namespace ifab::experiments {
namespace {
namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path FreshDir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("ifab_run_folder_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string Read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(AtomicFile, ReplacesTheFileOnlyWhenComplete) {
  const fs::path dir = FreshDir("atomic");
  const fs::path file = dir / "results.json";
  WriteFileAtomically(file, "old\n");
  {
    AtomicOfstream out(file);
    out << "new, half written";
    // Not committed yet: readers still see the old file, whole.
    EXPECT_EQ(Read(file), "old\n");
  }
  EXPECT_EQ(Read(file), "new, half written");
  // A writer abandoned by an exception leaves the old file and no temporary behind.
  try {
    AtomicOfstream out(file);
    out << "broken";
    throw std::runtime_error("failure while writing");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(Read(file), "new, half written");
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST(RunFolder, IsNotOverwrittenWithoutForce) {
  const fs::path dir = FreshDir("no_overwrite");
  RunOptions o;
  o.experiment = "lrf-bias";
  o.out_dir = dir.string();
  o.progress = false;
  RunExperiment(o);
  const std::string first = Read(dir / "results.json");
  ASSERT_FALSE(first.empty());
  EXPECT_THAT(testing::ErrorOf([&] { RunExperiment(o); }),
              HasSubstr("the folder already holds a run (results.json); choose another folder or pass --force"));
  EXPECT_EQ(Read(dir / "results.json"), first);
  o.force = true;
  EXPECT_NO_THROW(RunExperiment(o));
}

// `ifab run` as a user runs it, stopped by SIGINT once its first run has finished.
TEST(RunFolder, SigintLeavesAConsistentFolderMarkedInterrupted) {
  const fs::path dir = FreshDir("sigint") / "out";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl(IFAB_BINARY, IFAB_BINARY, "run", "lrf-bias", "--runs", "200", "--jobs", "1", "--quiet", "--out",
          dir.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  while (!fs::exists(dir / "run_001" / "results.json") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(fs::exists(dir / "run_001" / "results.json")) << "the runs did not start";
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal instead of stopping cleanly";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const nlohmann::json r = nlohmann::json::parse(Read(dir / "results.json"));
  EXPECT_TRUE(r.at("interrupted").get<bool>());
  const int finished = r.at("runs_finished").get<int>();
  EXPECT_GE(finished, 2);
  EXPECT_LT(finished, 200);
  // Every finished run has whole results; nothing half-written is left.
  int with_results = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_directory()) {
      EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << e.path();
      continue;
    }
    if (fs::exists(e.path() / "results.json")) {
      ++with_results;
      EXPECT_NO_THROW(nlohmann::json::parse(Read(e.path() / "results.json"))) << e.path();
    }
    for (const auto& f : fs::directory_iterator(e.path()))
      EXPECT_EQ(f.path().string().find(".tmp."), std::string::npos) << f.path();
  }
  EXPECT_EQ(with_results, finished);
}

}  // namespace
}  // namespace ifab::experiments
