// The launcher and huge pages (cli/launcher.cpp, cli/huge_pages.h): which runs ask for them and
// with what, that the launcher passes its arguments on and the output does not change, and
// that it says so when its program is missing.
#include "huge_pages.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "run_vcut.h"

namespace {
namespace fs = std::filesystem;
using vcut::cli::huge_page_tunables;
using vcut::cli::test::run_vcut;
using vcut::cli::test::write;

constexpr const char* kMadvise = "always [madvise] never\n";

TEST(HugePages, OnlyTheCommandsThatCutRestart) {
  EXPECT_EQ(huge_page_tunables("simulate", nullptr, kMadvise), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(huge_page_tunables("study", nullptr, kMadvise), "glibc.malloc.hugetlb=1");
  for (const char* command : {"program", "poses", "check", "compensate", "machine", "job", "--help", "simulat"})
    EXPECT_FALSE(huge_page_tunables(command, nullptr, kMadvise)) << command;
  EXPECT_FALSE(huge_page_tunables(nullptr, nullptr, kMadvise));
}

TEST(HugePages, OnlyWhereTheKernelGivesThemWhenAsked) {
  EXPECT_FALSE(huge_page_tunables("simulate", nullptr, "[always] madvise never\n"));
  EXPECT_FALSE(huge_page_tunables("simulate", nullptr, "always madvise [never]\n"));
  EXPECT_FALSE(huge_page_tunables("simulate", nullptr, ""));
  EXPECT_FALSE(huge_page_tunables("simulate", nullptr, nullptr));
}

TEST(HugePages, OtherTunablesAreKeptAndAChoiceAlreadyMadeIsNotOverridden) {
  EXPECT_EQ(huge_page_tunables("simulate", "", kMadvise), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(huge_page_tunables("simulate", "glibc.malloc.arena_max=2", kMadvise),
            "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1");
  // =0 is the user's refusal, =1 a choice already made.
  EXPECT_FALSE(huge_page_tunables("simulate", "glibc.malloc.hugetlb=1", kMadvise));
  EXPECT_FALSE(huge_page_tunables("simulate", "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=0", kMadvise));
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The same job with huge pages asked for (GLIBC_TUNABLES unset) and refused (=0): a folder name
// with a space in it and several flags, so that an argument the launcher lost or split shows.
TEST(HugePages, TheLauncherPassesItsArgumentsOnAndTheOutputIsTheSame) {
  const fs::path dir = vcut::cli::test::fresh_test_dir("vcut huge pages ");
  write(dir / "tools.yaml", "tools:\n  1: {type: ball, diameter: 6, flute_length: 20, length: 40}\n");
  write(dir / "p.ngc",
        "%\nG17 G21 G90 G94 G54\nT1 M6\nS10000 M3\nG0 X-5 Y10 Z5\nG1 Z-1.5 F800\nG1 X25 Y14 Z-2\nG1 Y20\nG0 "
        "Z5\nM30\n%\n");
  write(dir / "job.yaml",
        "job: hp\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: p.ngc}\noffsets: {G54: [0, 0, 0]}\n"
        "stock: {box: {min: [0, 0, -6], max: [20, 30, 0]}}\nengine: {kind: dexel, resolution: 0.2, threads: 1}\n"
        "report: {out: out}\n");
  const std::string job = "'" + (dir / "job.yaml").string() + "'";
  auto run = [&](const std::string& env, const std::string& out) {
    return run_vcut("simulate " + job + " --quiet --threads 2 --resolution 0.1 --out '" + (dir / out).string() + "'",
                    env);
  };
  const auto asked = run("env -u GLIBC_TUNABLES", "out asked");
  const auto refused = run("env GLIBC_TUNABLES=glibc.malloc.hugetlb=0", "out refused");
  ASSERT_EQ(asked.exit_code, 0) << asked.output;
  ASSERT_EQ(refused.exit_code, 0) << refused.output;
  const std::string stl = read_file(dir / "out asked" / "machined.stl");
  EXPECT_GT(stl.size(), 1000u);
  EXPECT_EQ(stl, read_file(dir / "out refused" / "machined.stl"));
  // The flags reached the program: its report says 2 threads and v = 0.1 mm.
  const std::string report = read_file(dir / "out asked" / "report.json");
  EXPECT_NE(report.find("\"threads\": 2"), std::string::npos) << report.substr(0, 2000);
  EXPECT_NE(report.find("\"resolution_mm\": 0.1"), std::string::npos) << report.substr(0, 2000);
  // Run through the dynamic loader, /proc/self/exe is the loader: the launcher finds vcut-core
  // by its own path (argv[0]) there.
  const fs::path loader = "/lib64/ld-linux-x86-64.so.2";  // x86-64's, where the project builds
  if (fs::exists(loader)) {
    // (A sanitized vcut so started finds the loader's own 520 bytes from dl-open a leak.)
    const auto loaded = run("env -u GLIBC_TUNABLES ASAN_OPTIONS=detect_leaks=0 " + loader.string(), "out loaded");
    ASSERT_EQ(loaded.exit_code, 0) << loaded.output;
    EXPECT_EQ(stl, read_file(dir / "out loaded" / "machined.stl"));
  }
  fs::remove_all(dir);
}

// The launcher alone, without vcut-core beside it: a one-line internal error naming what it
// could not start, not a crash or a silent success.
TEST(HugePages, ALauncherWithoutItsProgramSaysSo) {
  const fs::path dir = vcut::cli::test::fresh_test_dir("vcut_launcher_");
  fs::copy_file(vcut::cli::test::vcut_binary(), dir / "vcut");
  fs::permissions(dir / "vcut", fs::perms::owner_all);
  const auto r = vcut::cli::test::run_command((dir / "vcut").string() + " program nothing.ngc");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("vcut: internal error: cannot start " + (dir / "vcut-core").string()), std::string::npos)
      << r.output;
  fs::remove_all(dir);
}

}  // namespace
