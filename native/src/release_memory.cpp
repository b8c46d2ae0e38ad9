#include "pointscale/detail/release_memory.h"

#include <cstdlib>  // defines __GLIBC__ on glibc

#if defined(__GLIBC__)
#include <malloc.h>
#elif defined(__APPLE__)
#include <malloc/malloc.h>
#elif defined(_WIN32)
#include <malloc.h>
#endif

namespace pointscale {

// Each C library's own call, where it has one; musl and others keep their pages.
void release_free_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#elif defined(__APPLE__)
  malloc_zone_pressure_relief(nullptr, 0);  // every zone, all it can
#elif defined(_WIN32)
  _heapmin();  // the CRT heap's free pages, back to Windows
#endif
}

}  // namespace pointscale
