#pragma once
//! \file huge_page_malloc.h
//! \brief The command-line programs' opt-in to glibc's transparent-huge-page malloc.
//! \details On a kernel that gives transparent huge pages only where asked (THP mode `madvise`, Debian's
//! default), every first touch of a 4 KiB page of the heap is a page fault, and the hierarchy, the
//! meshing and the export touch fresh memory all the time (OpenMesh's and CGAL's vectors, many small
//! ones: the library advises its own large buffers, huge_pages.h, but cannot reach those). glibc 2.35+
//! asks for huge pages for its whole heap when started with `GLIBC_TUNABLES=glibc.malloc.hugetlb=1`,
//! which can only be set before the process starts. Measured on the project's machine (one thread,
//! CPU): the 1M-point build −20%, a 10,000-tile mesh −13%, a 1M-point 3D Tiles export from stored
//! levels −45%; peak memory +2–4%; every output byte-identical. A library does not choose its host's
//! allocator, so this is for the programs (`mrtile`, `bench`), which are hosts.

#include <string>

namespace mrt::tools {

//! Re-executes the running program (/proc/self/exe, same arguments) with glibc.malloc.hugetlb=1 added
//! to GLIBC_TUNABLES, and returns only when it does not: not Linux with glibc 2.35 or later, THP not in
//! `madvise` mode (with `always` every heap already gets huge pages, with `never` none can), the
//! environment already names glibc.malloc.hugetlb (the re-executed program itself, or a user's own
//! choice: `GLIBC_TUNABLES=glibc.malloc.hugetlb=0` turns this off), under valgrind (it would not follow
//! the exec), or the exec failed. Call first thing in main(), before any output or thread.
void use_huge_page_malloc(char** argv);

//! What this process's heap runs with, for reports: "glibc.malloc.hugetlb=N" when GLIBC_TUNABLES sets
//! it, else "the default malloc".
const std::string& heap_setting();

} // namespace mrt::tools
