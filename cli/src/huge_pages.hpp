#pragma once
// Large arrays in transparent huge pages. A national network's adjustment
// or a large tile touches gigabytes of fresh memory, and on a machine whose
// kernel gives huge pages only on request (transparent_hugepage=madvise,
// Debian's default) each 4 kB page is a fault: measured at 10⁵ stations,
// 600 000 faults and a third of `geoanchor adjust`'s time (docs/scale.md).
// glibc's malloc asks for huge pages when its tunable glibc.malloc.hugetlb=1
// is set, and it reads tunables only when a process starts.

namespace geoanchor::cli {

// Call first in main, before any thread starts (the restart costs a start
// of the program: for the commands that touch much memory): when the kernel gives huge
// pages on request (madvise) and GLIBC_TUNABLES is not set, starts this
// program again (the same process, /proc/self/exe with `argv`) with
// GLIBC_TUNABLES=glibc.malloc.hugetlb=1. Returns, changing nothing, when
// GLIBC_TUNABLES is set already (the user's own, or after the restart), the
// kernel gives huge pages always or never, or the restart cannot be made.
void restart_with_huge_pages(char** argv);

}  // namespace geoanchor::cli
