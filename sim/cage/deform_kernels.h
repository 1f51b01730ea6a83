// The inner loops of Embedding::deform: rows of (render points) = W · (cage points), in float.
// Each is compiled twice — for any x86-64 and for AVX2 + FMA (8 lanes, fused multiply-add) —
// and deformKernelIsa() picks the one the CPU runs: the render-mesh deform is bound by these
// multiply-adds (the seed-scale scene deforms 90 M weights per frame). The two give results
// that differ in rounding only (FMA rounds once); on one machine the choice is fixed, so results
// stay bit-identical run to run.
#pragma once

namespace sb::cage {

enum class DeformIsa { Baseline, Avx2Fma };

// The best of the two this CPU can run.
DeformIsa deformKernelIsa();

// out[3i … 3i+2] = Σ_j W[i·m + j] · (X[j], Y[j], Z[j]) for rows i in [begin, end): W row-major
// with m columns (cage vertices), X, Y, Z the cage coordinates (m each, metres). `cached`: the
// rows are in cache (a W of a few MB, used for several cages), so they are taken four at a
// time (1.6–1.9× faster there; streamed from memory, one at a time was 1.5× faster: measured
// on the 2-core EPYC VM). The two differ in rounding only.
void denseDeformRows(const float* W, int m, const float* X, const float* Y, const float* Z,
                     float* out, int begin, int end, bool cached, DeformIsa isa);

// The same for a compressed row-major sparse W (outer: rows + 1 offsets into inner/values),
// with the cage as (x, y, z, 0) quadruples: cage4[4j … 4j+3], 16-byte aligned.
void sparseDeformRows(const int* outer, const int* inner, const float* values, const float* cage4,
                      float* out, int begin, int end, DeformIsa isa);

}  // namespace sb::cage
