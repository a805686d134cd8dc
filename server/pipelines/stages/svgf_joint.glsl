// The joint chain's per-signal access (svgf_variance, svgf_atrous with
// SIGNALS 2: split diffuse and specular filtered in the same passes). Signal
// 0 reads `guide` and `temporal`, signal 1 `temporal2` and, with
// SECOND_GUIDE (features of its own: reflect's specular), `guide2`; the
// including pass declares all four and SIGNALS and SECOND_GUIDE. Call these
// with s a constant of an unrolled loop, so each selection is resolved at
// compile time (llvmpipe would otherwise load both sides).
#ifndef DN_SVGF_JOINT_GLSL
#define DN_SVGF_JOINT_GLSL

#define NS SIGNALS

// Signal s's guide: 0 the shared one, 1 guide2.
int dn_guide_of(int s) { return SECOND_GUIDE && s == 1 ? 1 : 0; }
uvec4 dn_guide_load(int g, uint i) { return g == 0 ? guide_at(i) : guide2_at(i); }
// NS == 1 also resolves a run-time s: one signal never touches its unbound second buffers.
vec4 dn_temporal_load(int s, uint i) { return s == 0 || NS == 1 ? temporal_at(i) : temporal2_at(i); }
// Whether s is the last signal (the one SPECULAR_ALPHA, CLASS_EDGES and
// SPATIAL_BANDWIDTH refer to: reflect's specular).
bool dn_last_signal(int s) { return s == NS - 1; }

#endif
