// The process's allocator. Where the build links mimalloc (CMakeLists.txt: not in sanitizer
// builds), it serves every allocation in the process, lavapipe's shader compiler and LLVM
// included, and this asks it for 2 MiB pages (transparent huge pages, by madvise). A process
// touches tens of megabytes once (lavapipe's NIR passes, the film's host copy, the EXR's
// buffers); with 4 KiB pages each first touch is a page fault, and on the virtual machines this
// was measured on a fault costs about 10 us: a 16-spp render of Tungsten's Cornell box spent 0.1 s
// of its 0.45 s in them on 2026-12-06's machine; on a Zen 3 one the 2 MiB pages saved 2-8% of the
// process (docs/BENCHMARKS.startup-notes.md).
#ifdef TELESCOPE_MIMALLOC
#include <sys/mman.h>

#include <cstdint>

#include <mimalloc.h>

namespace {

const bool kLargePages = [] {
    mi_option_enable(mi_option_large_os_pages);
    // The option holds for segments mimalloc maps from now on; the main thread's first segment
    // was mapped before main, with small pages, and would serve most of what this thread
    // allocates. mimalloc 2 aligns segments to their 32 MiB size: the advice covers the one this
    // allocation lies in. (Where that does not hold the call fails, harmlessly: only speed is lost.)
    constexpr uintptr_t kSegmentBytes = uintptr_t(32) << 20;
    void* probe = mi_malloc(16);
    const uintptr_t segment = reinterpret_cast<uintptr_t>(probe) & ~(kSegmentBytes - 1);
    madvise(reinterpret_cast<void*>(segment), kSegmentBytes, MADV_HUGEPAGE);
    mi_free(probe);
    return true;
}();

}  // namespace
#endif
