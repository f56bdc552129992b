#include "huge_pages.h"

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

void ask_for_huge_pages(int argc, char** argv) {
#if defined(__linux__) && defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  if (argc < 2) return;
  char mode[128] = {};
  if (std::FILE* f = std::fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r")) {
    const std::size_t n = std::fread(mode, 1, sizeof mode - 1, f);
    mode[n] = '\0';
    std::fclose(f);
  }
  if (const std::optional<std::string> value = huge_page_tunables(argv[1], std::getenv("GLIBC_TUNABLES"), mode))
    ::setenv("GLIBC_TUNABLES", value->c_str(), 1);
#else
  (void)argc;
  (void)argv;
#endif
}

}  // namespace vcut::cli
