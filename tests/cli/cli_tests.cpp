// Most of the command-line tests, in one translation unit: each is small beside the headers it
// includes (gtest's, JSON's), which took most of their compile time, nine times over
// (tests/CMakeLists.txt). The pose and servo tests stay apart: each has a CSV reader of its own.
#include "check_cli_test.cpp"
#include "cli_test.cpp"
#include "huge_pages_test.cpp"
#include "machine_check_cli_test.cpp"
#include "machine_cli_test.cpp"
#include "program_alone_cli_test.cpp"
#include "program_cli_test.cpp"
#include "study_cli_test.cpp"
