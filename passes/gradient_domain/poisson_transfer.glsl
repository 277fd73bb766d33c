// PoissonReconstruct, multigrid transfers between a level and the next coarser one
// (cell-centred, coarse cell c covers fine cells 2c and 2c+1; an odd last fine cell has a
// coarse cell of its own). Prolongation P is bilinear between coarse cell centres, 3/4 and 1/4
// per axis, with Neumann (clamped) boundaries; restriction is R = P^T / 4, so the V-cycle is a
// symmetric preconditioner and CG stays valid.
#ifndef POISSON_TRANSFER_GLSL
#define POISSON_TRANSFER_GLSL

// Weight of coarse cell c in the 1D interpolation of fine cell f (nc coarse cells).
float poisson_prolong_weight(int f, int c, int nc) {
    int parent = f >> 1;
    int other = (f & 1) != 0 ? parent + 1 : parent - 1;
    bool clamped = other < 0 || other >= nc;
    float w = 0.0;
    if (c == parent) w += clamped ? 1.0 : 0.75;
    if (c == other && !clamped) w += 0.25;
    return w;
}

#endif
