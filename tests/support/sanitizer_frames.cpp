// Sanitizer trees only (SCATTERLAB_SANITIZE): large aligned blocks recycled instead of mapped
// afresh each time, so that Mesa's llvmpipe does not spend the sanitizer suite in page faults.
//
// llvmpipe runs a compute shader that synchronises a workgroup (barrier(): the tracer's
// reductions, the scans) as LLVM coroutines, and its JIT-compiled code allocates the coroutine
// frames of each workgroup with posix_memalign (0.3–2.5 MB) and frees them when the workgroup
// ends. glibc's heap reuses such blocks; AddressSanitizer serves every block above its size
// classes with a fresh mmap and unmaps it after the quarantine, so each workgroup faults its
// frames' pages in again: GpuAdaptiveMethod.DefaultLevelsFollowTheInitialSamplesAsOnCpu spent
// half its CPU time in the kernel (32 000 such blocks, 5.6 M page faults; docs/reliability.md,
// "CI's time").
//
// The runtime defines posix_memalign and free as weak aliases of its interceptors; the strong
// definitions here take their place in every executable of the tree. posix_memalign serves
// blocks of at least kMinBytes from one reserved range, recycled by size; everything else, and
// free of a pointer outside the range, goes to the sanitizer as before. Only posix_memalign's
// large blocks are recycled: scatterlab's own allocations (new, malloc, aligned new) are
// untouched and keep every check. The blocks are not scanned by LeakSanitizer: llvmpipe keeps no
// heap pointers in a coroutine frame past its workgroup.
#include <sys/mman.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>

extern "C" int __interceptor_posix_memalign(void** out, std::size_t alignment, std::size_t size);
extern "C" void __interceptor_free(void* p);

namespace {

constexpr std::size_t kMinBytes = std::size_t(128) << 10;  // ASan's largest size class
constexpr std::size_t kGrain = std::size_t(64) << 10;      // blocks start on a grain
constexpr std::size_t kRange = std::size_t(32) << 30;      // address space, reserved lazily
constexpr std::size_t kMaxGrains = 4096;                   // blocks up to 256 MB are recycled
constexpr std::size_t kSlots = kRange / kGrain;

// Constant-initialised (no constructor runs): posix_memalign and free may be called before
// any static initialiser.
struct Recycler {
  std::mutex mutex;
  std::size_t used = 0;               // grains handed out from base, ever
  void* heads[kMaxGrains + 1] = {};   // free blocks by size in grains, linked through their
                                      // first word
  std::uint16_t grains[kSlots] = {};  // size in grains of the block starting at each grain
};

constinit Recycler gRecycler;

// The reserved range's start, set once. Every free in the process reads it: on a cache line of
// its own, away from the mutex the lock writes (beside it, DefaultLevelsFollowTheInitialSamples-
// AsOnCpu and AdaptiveUnderABindingBudgetAsAFreshRender in one process took 22.5 s, 9.9 s here).
alignas(64) constinit std::atomic<char*> gBase{nullptr};

bool inRange(const void* p) {
  const char* base = gBase.load(std::memory_order_acquire);
  return base && p >= base && p < base + kRange;
}

}  // namespace

extern "C" int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  if (size < kMinBytes || alignment > kGrain)
    return __interceptor_posix_memalign(out, alignment, size);
  const std::size_t n = (size + kGrain - 1) / kGrain;
  if (n > kMaxGrains) return __interceptor_posix_memalign(out, alignment, size);
  Recycler& r = gRecycler;
  std::lock_guard<std::mutex> lock(r.mutex);
  char* base = gBase.load(std::memory_order_relaxed);
  if (!base) {
    void* m = mmap(nullptr, kRange, PROT_READ | PROT_WRITE,
                   MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (m == MAP_FAILED) return __interceptor_posix_memalign(out, alignment, size);
    base = static_cast<char*>(m);
    gBase.store(base, std::memory_order_release);
  }
  if (void* head = r.heads[n]) {
    r.heads[n] = *static_cast<void**>(head);
    *out = head;
    return 0;
  }
  if (r.used + n > kSlots) return __interceptor_posix_memalign(out, alignment, size);
  r.grains[r.used] = static_cast<std::uint16_t>(n);
  *out = base + r.used * kGrain;
  r.used += n;
  return 0;
}

extern "C" void free(void* p) {
  if (!inRange(p)) {
    __interceptor_free(p);
    return;
  }
  Recycler& r = gRecycler;
  std::lock_guard<std::mutex> lock(r.mutex);
  const std::size_t offset =
      static_cast<std::size_t>(static_cast<char*>(p) - gBase.load(std::memory_order_relaxed));
  const std::size_t n = offset % kGrain == 0 ? r.grains[offset / kGrain] : 0;
  if (n == 0) {  // not a block's start: the sanitizer reports the bad free
    __interceptor_free(p);
    return;
  }
  *static_cast<void**>(p) = r.heads[n];
  r.heads[n] = p;
}
