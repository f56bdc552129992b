// Runs the real `vcut` binary as a user does (vcut_binary()) and
// checks its one-line errors; shared by the command-line tests.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace vcut::cli::test {

// The path of the `vcut` binary this build made: cli/vcut beside this test's tests/ folder
// in the same build folder (read at run time, so that the test sources compile alike in the
// Release and the sanitizer builds and ccache compiles them once).
inline const char* vcut_binary() {
  static const std::string path =
      (std::filesystem::read_symlink("/proc/self/exe").parent_path().parent_path() / "cli" / "vcut").string();
  return path.c_str();
}

struct CommandResult {
  int exit_code;
  std::string output;  // stdout and stderr
};

// A shell command line, its stderr with its stdout.
inline CommandResult run_command(const std::string& command) {
  CommandResult r{-1, ""};
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  char buffer[4096];
  while (pipe && std::fgets(buffer, sizeof buffer, pipe)) r.output += buffer;
  const int status = pipe ? ::pclose(pipe) : -1;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// `prefix`: in front of the binary on the shell's line (env VAR=value, ...).
inline CommandResult run_vcut(const std::string& args, const std::string& prefix = "") {
  return run_command(prefix + (prefix.empty() ? "" : " ") + std::string(vcut_binary()) + " " + args);
}

// An empty folder of its own for the running test: <tmp>/<prefix><test name>.
inline std::filesystem::path fresh_test_dir(const std::string& prefix) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    (prefix + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

// A bundled machine file's text (examples/machines/NAME.yaml) to be written elsewhere: its
// models' relative paths made absolute, so that the copy still finds them.
inline std::string bundled_machine_text(const std::string& name) {
  const std::string folder = std::string(VCUT_SOURCE_DIR) + "/examples/machines/";
  std::ifstream in(folder + name + ".yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (std::size_t at = text.find("file: models/"); at != std::string::npos; at = text.find("file: models/", at + 1))
    text.insert(at + 6, folder);
  return text;
}

// A bad input: exit code 2 and one line "vcut: error: ..." containing `fragment`.
inline void expect_error(const CommandResult& r, const std::string& fragment) {
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("vcut: error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

}  // namespace vcut::cli::test
