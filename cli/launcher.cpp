// vcut: the command line's front door. It starts the program, vcut-core beside it, with the
// same arguments, and for a run that cuts first asks glibc's malloc for transparent huge pages
// (huge_pages.h): a setting glibc reads at start-up only, given here before vcut-core's 51
// shared libraries load, where vcut-core restarting itself would load them twice (0.1 s).
// No library of vcut's: this start-up costs about a millisecond.
#include <sys/auxv.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "huge_pages.h"

namespace {

// The folder of this program: /proc/self/exe where the kernel started it (through its
// interpreter, AT_BASE); run as `ld-linux.so vcut ...` that is the loader, and argv[0] is
// this program's path.
std::string own_folder(const char* argv0) {
  char path[PATH_MAX];
  std::string own;
  if (::getauxval(AT_BASE) != 0) {
    const ssize_t n = ::readlink("/proc/self/exe", path, sizeof path);
    if (n > 0 && static_cast<std::size_t>(n) < sizeof path) own.assign(path, static_cast<std::size_t>(n));
  }
  if (own.empty() && argv0 != nullptr && ::realpath(argv0, path) != nullptr) own = path;
  return own.empty() ? std::string(".") : own.substr(0, own.rfind('/'));
}

}  // namespace

int main(int argc, char** argv) {
  vcut::cli::ask_for_huge_pages(argc, argv);
  const std::string core = own_folder(argc > 0 ? argv[0] : nullptr) + "/vcut-core";
  ::execv(core.c_str(), argv);
  std::fprintf(stderr, "vcut: internal error: cannot start %s: %s\n", core.c_str(), std::strerror(errno));
  return 1;
}
