// Parameters of the backward passes; mirrors `render::backward::BackwardParams` (std430, pointers first).
// Gradient accumulators are `GradBuf`: Floats updated with float atomics, or Uints updated with a
// compare-and-swap loop on devices without VK_EXT_shader_atomic_float (the *_cas shader variants).
#include "grad_add.glsl"

layout(buffer_reference, std430, buffer_reference_align = 8) buffer BackwardParams {
    // upstream gradients dL/d(output), planar like the forward outputs (width * height per plane)
    Floats dl_drgb;             // 3 planes
    Floats dl_dalpha;
    Floats dl_ddepth;           // of the accumulated depth sum w_i z_i
    Floats dl_dexpected_depth;
    Floats dl_dfeatures;        // feature_dim planes
    // per-view gradients of the projected quantities, accumulated by the blend backward pass and
    // consumed by the projection backward pass; zeroed by the host before each view's blend backward
    GradBuf grad_xy;            // 2N
    GradBuf grad_conic;         // 3N, (a, b, c)
    GradBuf grad_opacity;       // N, of the activated opacity
    GradBuf grad_color;         // 3N
    GradBuf grad_depth;         // N
    GradBuf grad_features;      // N * D
    // gradients of the stored parameters, accumulated over views by the projection backward pass
    Floats grad_means;          // 3N
    Floats grad_log_scales;     // 3N
    Floats grad_quats;          // 4N
    Floats grad_opacity_logits; // N
    Floats grad_sh;             // N * K * 3
    // densification statistics: sum over views of |dL/d(mean2d)| in NDC units, and the view count
    Floats grad_xy_norm_sum;    // N
    Uints grad_xy_views;        // N
    uint use_alpha;             // dl_dalpha holds data
    uint use_depth;             // dl_ddepth / dl_dexpected_depth hold data
    uint pad0;
    uint pad1;
};
