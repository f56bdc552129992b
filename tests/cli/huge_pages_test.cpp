// The restart for huge pages (cli/huge_pages.h): which runs restart and with what, and that a
// restarted run keeps its arguments and writes the same bytes as one that is not.
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
  // A restarted run names it (no second restart), and =0 is the user's refusal.
  EXPECT_FALSE(huge_page_tunables("simulate", "glibc.malloc.hugetlb=1", kMadvise));
  EXPECT_FALSE(huge_page_tunables("simulate", "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=0", kMadvise));
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The same job with the restart (GLIBC_TUNABLES unset) and without it (=0): a folder name with a
// space in it and several flags, so that an argument lost or split on the way shows.
TEST(HugePages, ARestartedRunKeepsItsArgumentsAndItsOutput) {
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
  const auto restarted = run("env -u GLIBC_TUNABLES", "out restarted");
  const auto kept = run("env GLIBC_TUNABLES=glibc.malloc.hugetlb=0", "out kept");
  ASSERT_EQ(restarted.exit_code, 0) << restarted.output;
  ASSERT_EQ(kept.exit_code, 0) << kept.output;
  const std::string stl = read_file(dir / "out restarted" / "machined.stl");
  EXPECT_GT(stl.size(), 1000u);
  EXPECT_EQ(stl, read_file(dir / "out kept" / "machined.stl"));
  // The flags reached the restarted run: its report says 2 threads and v = 0.1 mm.
  const std::string report = read_file(dir / "out restarted" / "report.json");
  EXPECT_NE(report.find("\"threads\": 2"), std::string::npos) << report.substr(0, 2000);
  EXPECT_NE(report.find("\"resolution_mm\": 0.1"), std::string::npos) << report.substr(0, 2000);
  // Run through the dynamic loader (as scripts/device-bundle does), /proc/self/exe is the
  // loader: no restart there (the loader would take `simulate` for the program to load).
  const auto loaded = run("env -u GLIBC_TUNABLES /lib64/ld-linux-x86-64.so.2", "out loaded");
  ASSERT_EQ(loaded.exit_code, 0) << loaded.output;
  EXPECT_EQ(stl, read_file(dir / "out loaded" / "machined.stl"));
  fs::remove_all(dir);
}

}  // namespace
