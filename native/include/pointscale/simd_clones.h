// Marks a hot kernel to be built twice, for AVX2+FMA and for the baseline, with the one to run
// picked when the module loads: the wheel must run on any x86-64, and the kernels' loops over
// neighbours are four doubles wide with AVX2 instead of two.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define POINTSCALE_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define POINTSCALE_CLONES
#endif
