// Resampling MIS weights of reuse between path reservoirs (Lin et al. 2022, Sec. 7): the
// pairwise and defensive pairwise weights of spatial reuse; temporal reuse uses the
// two-technique generalized balance heuristic (mis.glsl mis_balance2) directly. Failed shifts
// enter as a target of 0, never as a confidence that contributed.
#ifndef LOOM_RESTIR_REUSE_MIS_GLSL
#define LOOM_RESTIR_REUSE_MIS_GLSL

#include "lib/mis.glsl"

// Defensive pairwise MIS (Bitterli 2022, Sec. 9.1.3; Lin et al. 2022, Sec. 7.2). With k valid
// neighbours every weight is divided by k + 1:
//   neighbour q, for its shifted sample x:  m_q(x) = balance(M_q p_hat_q, M_c p_hat_c)(x)
//   canonical, for its own sample x:        m_c(x) = 1 + sum_q (1 - balance(M_q p_hat_q, M_c p_hat_c)(x))
// where p_hat_q(x) is the target of x shifted into q's domain (0 when that shift fails).
float pairwise_neighbour_weight(float M_q, float t_q, float M_c, float t_c) {
    return mis_balance2(M_q, t_q, M_c, t_c);
}
float pairwise_canonical_term(float M_q, float t_q, float M_c, float t_c) {
    return 1.0 - mis_balance2(M_q, t_q, M_c, t_c);
}

#endif
