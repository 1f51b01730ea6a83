// Whether this test binary runs under a sanitizer. CI runs the whole suite under AddressSanitizer
// (with UBSan) and under ThreadSanitizer, 10-15x slower than the optimised build; the few tests
// that would take minutes there shorten or skip their slowest cases, and say so where they do.
// GCC announces the sanitizers with __SANITIZE_ADDRESS__ / __SANITIZE_THREAD__, clang through
// __has_feature.
#pragma once

namespace sb::test_support {

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

#if defined(__SANITIZE_THREAD__)
inline constexpr bool kThreadSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
inline constexpr bool kThreadSanitizer = true;
#else
inline constexpr bool kThreadSanitizer = false;
#endif
#else
inline constexpr bool kThreadSanitizer = false;
#endif

inline constexpr bool kSanitized = kAddressSanitizer || kThreadSanitizer;

}  // namespace sb::test_support
