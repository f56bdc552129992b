#include "huge_pages.h"

#include <sys/auxv.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace vcut::cli {

std::optional<std::string> huge_page_tunables(const char* command, const char* tunables, const char* thp_mode) {
  if (thp_mode == nullptr || std::strstr(thp_mode, "[madvise]") == nullptr) return std::nullopt;
  if (command == nullptr || (std::strcmp(command, "simulate") != 0 && std::strcmp(command, "study") != 0))
    return std::nullopt;
  constexpr const char* kTunable = "glibc.malloc.hugetlb";
  if (tunables != nullptr && std::strstr(tunables, kTunable) != nullptr) return std::nullopt;
  std::string value = tunables != nullptr && *tunables != '\0' ? std::string(tunables) + ":" : std::string();
  return value + kTunable + "=1";
}

void restart_with_huge_pages(int argc, char** argv) {
#if defined(__linux__) && defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  // Started by the kernel through its interpreter (AT_BASE, where the dynamic loader lies), so
  // that /proc/self/exe is this program; run as `ld-linux.so vcut ...` (scripts/device-bundle)
  // it is the loader, which would take the command for the program to load.
  if (argc < 2 || ::getauxval(AT_BASE) == 0) return;
  char mode[128] = {};
  if (std::FILE* f = std::fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r")) {
    const std::size_t n = std::fread(mode, 1, sizeof mode - 1, f);
    mode[n] = '\0';
    std::fclose(f);
  }
  const std::optional<std::string> value = huge_page_tunables(argv[1], std::getenv("GLIBC_TUNABLES"), mode);
  if (!value || ::setenv("GLIBC_TUNABLES", value->c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
  // Not restarted (no /proc): go on as started.
#else
  (void)argc;
  (void)argv;
#endif
}

}  // namespace vcut::cli
