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
// GLIBC_TUNABLES at start-up only.
//
// The GLIBC_TUNABLES value the command `command` (argv[1]) restarts with, given the value it
// was started with (nullptr: unset) and the kernel's THP mode (the text of
// /sys/kernel/mm/transparent_hugepage/enabled, nullptr: none): the old value with
// glibc.malloc.hugetlb=1 added. None where the kernel gives huge pages only where asked does
// not hold ("[always]" gives them to every heap, "[never]" to none: the restart, about 0.1 s
// of start-up on the reference VM, would buy nothing), for a command that does not cut
// (simulate and study do), or where the old value names glibc.malloc.hugetlb already (a
// restarted run does; =0 keeps 4 KB pages).
std::optional<std::string> huge_page_tunables(const char* command, const char* tunables, const char* thp_mode);

// Where huge_page_tunables gives a value: sets it and replaces the process by the same program
// with the same arguments (the same process id, open files and working folder). Returns when
// it does not, or when the restart fails (the run then goes on with 4 KB pages). Does nothing
// under the address sanitizer, whose allocator is not glibc's, nor where the program was not
// started by its own name (run through the dynamic loader, /proc/self/exe is the loader).
void restart_with_huge_pages(int argc, char** argv);

}  // namespace vcut::cli
