// The few compiler-specific spellings the core needs, each with a path for GCC and Clang (Linux,
// macOS, MinGW), for MSVC (cl and clang-cl) and for any other C++17 compiler, so that no source
// file names a GCC-only feature directly. tests/test_portability.py cross-compiles the core for
// Windows and macOS to keep it so.
#pragma once
#include <cstring>
#include <type_traits>

// Forces a function inline even where the inliner would not, so that a kernel called from a
// multiversioned function (simd_clones.h) is compiled for that version's instruction set.
#if defined(__GNUC__) || defined(__clang__)
#define POINTSCALE_ALWAYS_INLINE __attribute__((always_inline)) inline
#elif defined(_MSC_VER)
#define POINTSCALE_ALWAYS_INLINE __forceinline
#else
#define POINTSCALE_ALWAYS_INLINE inline
#endif

// The same for a lambda, written after its parameter list (MSVC has no spelling for it before
// C++20, and inlines small lambdas anyway).
#if defined(__GNUC__) || defined(__clang__)
#define POINTSCALE_ALWAYS_INLINE_LAMBDA __attribute__((always_inline))
#else
#define POINTSCALE_ALWAYS_INLINE_LAMBDA
#endif

// GCC >= 11, Clang and MSVC >= 19.27 (which has no __has_builtin) have __builtin_bit_cast.
#if defined(__has_builtin)
#if __has_builtin(__builtin_bit_cast)
#define POINTSCALE_HAS_BUILTIN_BIT_CAST 1
#endif
#elif defined(_MSC_VER) && _MSC_VER >= 1927
#define POINTSCALE_HAS_BUILTIN_BIT_CAST 1
#endif

namespace pointscale {

// std::bit_cast (C++20) for C++17: the object representation of `from` as a To. The builtin
// where there is one (what GCC has always compiled here); the memcpy, for any other compiler,
// is the portable spelling that optimisers turn into the same register move. Always inlined, as
// the builtin is, so that it never stands as a call inside a vectorised loop of a clone.
template <class To, class From>
POINTSCALE_ALWAYS_INLINE To bit_cast(const From& from) noexcept {
  static_assert(sizeof(To) == sizeof(From), "bit_cast needs types of one size");
  static_assert(std::is_trivially_copyable<To>::value && std::is_trivially_copyable<From>::value,
                "bit_cast needs trivially copyable types");
#if defined(POINTSCALE_HAS_BUILTIN_BIT_CAST)
  return __builtin_bit_cast(To, from);
#else
  To to;
  std::memcpy(&to, &from, sizeof(To));
  return to;
#endif
}

}  // namespace pointscale
