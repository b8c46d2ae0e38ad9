// Hands freed heap pages back to the operating system. glibc keeps freed blocks of a few MB
// resident for reuse (its mmap threshold grows after the first large free), so without this a
// decomposition's peak RSS counts the temporaries of earlier levels again. macOS and Windows
// get their C library's own call (release_memory.cpp); a no-op elsewhere.
#pragma once

namespace pointscale {

void release_free_memory();

}  // namespace pointscale
