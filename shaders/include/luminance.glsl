// Luminance of linear Rec.709 / sRGB-primaries radiance.
#ifndef DN_LUMINANCE_GLSL
#define DN_LUMINANCE_GLSL

float dn_luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

#endif
