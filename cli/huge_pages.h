// Transparent huge pages for the heap of a run that cuts (glibc's malloc tunable).
#pragma once

#include <optional>
#include <string>

namespace vcut::cli {

// A run's meshes, rays and report buffers are large blocks each touched once, and with 4 KB
// pages a dexel run spends much of its time in page faults (D32 at 0.05 mm, 2 threads: 200,000
// faults and 2.0 of 14 CPU-seconds in the kernel on the reference VM, whose kernel gives huge
// pages only where asked: THP "madvise"). glibc's malloc asks for them (madvise on its heaps
// and large blocks) under the tunable glibc.malloc.hugetlb=1, which it reads from
// GLIBC_TUNABLES at start-up only: the launcher (cli/launcher.cpp) sets it before it starts
// the program.
//
// The GLIBC_TUNABLES value the command `command` (argv[1]) starts with, given the value the
// launcher was started with (nullptr: unset) and the kernel's THP mode (the text of
// /sys/kernel/mm/transparent_hugepage/enabled, nullptr: none): the old value with
// glibc.malloc.hugetlb=1 added. None where the kernel gives huge pages only where asked does
// not hold ("[always]" gives them to every heap, "[never]" to none), for a command that does
// not cut (simulate and study do), or where the old value names glibc.malloc.hugetlb already
// (=0 keeps 4 KB pages).
std::optional<std::string> huge_page_tunables(const char* command, const char* tunables, const char* thp_mode);

// Sets GLIBC_TUNABLES to huge_page_tunables' value for this process's arguments and kernel,
// where it gives one (under the address sanitizer, whose allocator is not glibc's, never).
void ask_for_huge_pages(int argc, char** argv);

}  // namespace vcut::cli
