// Colour helpers shared by every kernel.
#ifndef LOOM_COLOR_GLSL
#define LOOM_COLOR_GLSL

// Rec. 709 / sRGB primaries luminance.
float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// IEC 61966-2-1 sRGB transfer function.
vec3 linear_to_srgb(vec3 c) {
    c = max(c, vec3(0.0));
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}
vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

// Reinhard et al. 2002, Eq. 3 per channel.
vec3 tonemap_reinhard(vec3 c) { return c / (1.0 + c); }
// Narkowicz 2015 fit of the ACES filmic RRT+ODT.
vec3 tonemap_aces(vec3 c) {
    return clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0);
}

// Ramp for false-colour images: t in [0,1] -> dark blue, cyan, yellow, red.
vec3 colormap_jet(float t) {
    t = clamp(t, 0.0, 1.0);
    return clamp(vec3(1.5) - abs(4.0 * vec3(t) - vec3(3.0, 2.0, 1.0)), 0.0, 1.0);
}

#endif
