// Code generation of the lattice's hot loops (collide_stream.cpp, lb_kernel.cpp, lb_halo.cpp):
// included after the other headers, it applies to the functions below it
// in that file only.
#pragma once

#if defined(__AVX512F__) && !defined(__clang__)
// 8-wide vectors halve the instruction count of the collision (32 registers)
#pragma GCC target("prefer-vector-width=512")
#endif
#if defined(__GNUC__) && !defined(__clang__)
// keep the short per-population copies of the chunked kernel and of the
// halo's packing inline: a memcpy call per population and chunk costs more
// than the copy itself
#pragma GCC optimize("no-tree-loop-distribute-patterns")
#endif
