// The `vcut` binary under test. Its path differs between the Release and the sanitizer builds,
// so VCUT_BINARY is given to this file alone (tests/CMakeLists.txt): the other test sources
// compile to the same command in both builds, and ccache serves the second from the first.
#include "run_vcut.h"

namespace vcut::cli::test {

const char* vcut_binary() { return VCUT_BINARY; }

}  // namespace vcut::cli::test
