#pragma once
/// Resource bounds checked before work starts (docs/reliability.md, "Resource limits").
///
/// Memory: every large allocation a request implies (volumes: voxels × bytes, images, sample
/// sets, hash tables, fit working sets) is estimated from the values that determine it and
/// compared with one process-wide limit before anything is allocated. The default is 75 % of
/// physical memory; SCATTERLAB_MEMORY_LIMIT (read once, on first use) or setMemoryLimit()
/// (`scatterlab --memory-limit`) change it.

#include <cstdint>
#include <string>

namespace scatterlab {

/// The current memory limit in bytes.
std::uint64_t memoryLimit();
/// Sets the limit (bytes > 0); 0 restores the default (environment, else 75 % of RAM).
void setMemoryLimit(std::uint64_t bytes);
/// 75 % of physical memory (sysconf), the default when SCATTERLAB_MEMORY_LIMIT is unset; under
/// an address-space limit (RLIMIT_AS, `ulimit -v`) at most half of what it leaves above the
/// process's mapped size at the call (at least 1 MiB).
std::uint64_t defaultMemoryLimit();

/// Parses a size: bytes with an optional unit K, M, G, T (powers of 1024; "KiB", "MB", ...
/// accepted, case-insensitive), or a percentage of physical memory ("50%"). The result is
/// at least 1 MiB. Throws ConfigError naming `what` (e.g. "--memory-limit") on anything else.
std::uint64_t parseMemorySize(const std::string& text, const std::string& what);

/// "1.5 GiB", "512 MiB", "12 KiB", "100 bytes".
std::string formatBytes(double bytes);

/// Throws LimitError when `bytes` exceed memoryLimit(): "'KEY': WHAT needs about N GiB, above
/// the memory limit of M GiB (...how to change it)". `key` is the dotted key (or the file,
/// flag or option) whose value implies the allocation.
void checkMemory(const std::string& key, const std::string& what, double bytes);

}  // namespace scatterlab
