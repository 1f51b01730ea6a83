// The inner loops of Embedding::deform: rows of (render points) = W · (cage points), in float.
// Each is compiled for any x86-64, for AVX2 + FMA (8 lanes, fused multiply-add) and for AVX-512
// (16 lanes), and deformKernelIsa() picks the best the CPU runs: the render-mesh deform is bound
// by these multiply-adds (the seed-scale scene deforms 68 M weights per frame). The AVX2 and
// AVX-512 dense kernels give the same bits (the same fused chains); the baseline differs in
// rounding only (FMA rounds once). On one machine the choice is fixed, so results stay
// bit-identical run to run.
#pragma once

#include "sim/cage/panel_weights.h"

namespace sb::cage {

enum class DeformIsa { Baseline, Avx2Fma, Avx512 };

// Whether this CPU runs it, and the best it runs.
bool deformIsaSupported(DeformIsa isa);
DeformIsa deformKernelIsa();

// outs[k][3i … 3i+2] = Σ_j W(i, j) · (X_k[j], Y_k[j], Z_k[j]) for every row i of the panels
// [panelBegin, panelEnd) and every cage k < count. cages[k] holds X_k, Y_k, Z_k one after the
// other (W.cols() floats each, metres); outs[k] has 3 · W.rows() floats. A panel's rows are the
// vector lanes, and up to four (AVX-512: eight) cages share each load of a panel's column
// (twelve or 24 independent sums, no sums across lanes). Each row's result is one chain of
// multiply-adds in column order, whatever shares the call (how many cages, which panels, which
// thread): the same bits for a row in every call on one machine.
void panelDeformRows(const PanelWeights& W, const float* const* cages, float* const* outs,
                     int count, int panelBegin, int panelEnd, DeformIsa isa);

// The same for a compressed row-major sparse W (outer: rows + 1 offsets into inner/values),
// with the cage as (x, y, z, 0) quadruples: cage4[4j … 4j+3], 16-byte aligned; rows
// [begin, end) of out (3 floats per row).
void sparseDeformRows(const int* outer, const int* inner, const float* values, const float* cage4,
                      float* out, int begin, int end, DeformIsa isa);

}  // namespace sb::cage
