#pragma once
/// Whether this translation unit is built with AddressSanitizer (GCC: __SANITIZE_ADDRESS__,
/// Clang: __has_feature). ASan reserves some 15 TiB of shadow address space at start-up, so an
/// address-space limit (RLIMIT_AS, `ulimit -v`) cannot be used under it: media/vdb.cpp's
/// forked VDB parser and the tool's tests leave the limit off there.

namespace scatterlab {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

}  // namespace scatterlab
