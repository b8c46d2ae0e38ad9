// Marks a hot kernel to be built for AVX-512, for AVX2+FMA and for the baseline, with the one to
// run picked when the module loads: the wheel must run on any x86-64, and the kernels' loops
// over neighbours are eight doubles wide with AVX-512, four with AVX2 and two without.
// (GCC names the x86-64-v4 level from version 11 on; Clang has target_clones from 14 on.)
// Only on x86-64 ELF (Linux): the pick is an ifunc, which needs the ELF dynamic loader. Windows
// (COFF: MSVC has no target_clones, MinGW GCC refuses it), macOS (Mach-O: Apple's clang refuses
// it) and arm64 (NEON is the baseline, nothing to pick) build each kernel once, for the target.
#pragma once

#if defined(__x86_64__) && defined(__ELF__) && defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11
#define POINTSCALE_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#elif defined(__x86_64__) && defined(__ELF__) && defined(__GNUC__) && !defined(__clang__)
#define POINTSCALE_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#elif defined(__x86_64__) && defined(__ELF__) && defined(__clang__) && __clang_major__ >= 14
#define POINTSCALE_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define POINTSCALE_CLONES
#endif
