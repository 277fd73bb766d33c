// Lat-long environment maps: radiance lookup and importance sampling of the piecewise-constant
// 2D distribution built by core/scene/EnvMapDistribution (pbrt-v3 Sec. 13.6.7 / 14.2.4):
// pick a row from the marginal CDF, a column from that row's conditional CDF (binary search
// both), then convert the (u, v) density to solid angle with the lat-long Jacobian
// dw = 2 pi^2 sin(theta) du dv. Buffer layout: packEnvMapData in EnvMapDistribution.h.
// Mapping (Mitsuba 3 'envmap', local frame, y up): phi = 2 pi u, theta = pi v,
// d = (sin phi sin theta, cos theta, -cos phi sin theta); world = toWorld * local.
#ifndef LOOM_ENVMAP_GLSL
#define LOOM_ENVMAP_GLSL

#include "lib/sampling.glsl"

layout(std430) readonly buffer SceneEnvMaps { float envmap_data[]; };

uint envmap_u32(uint i) { return floatBitsToUint(envmap_data[i]); }
uint envmap_count() { return envmap_u32(0u); }
uint envmap_record(uint index) { return envmap_u32(1u + index); }
uvec2 envmap_size(uint index) {
    uint record = envmap_record(index);
    return uvec2(envmap_u32(record), envmap_u32(record + 1u));
}

// Three vec3 columns, each padded to 4 floats.
mat3 envmap_matrix(uint at) {
    return mat3(envmap_data[at], envmap_data[at + 1u], envmap_data[at + 2u],
                envmap_data[at + 4u], envmap_data[at + 5u], envmap_data[at + 6u],
                envmap_data[at + 8u], envmap_data[at + 9u], envmap_data[at + 10u]);
}

vec3 envmap_direction(vec2 uv) {
    float phi = 2.0 * PI * uv.x, theta = PI * uv.y;
    float s = sin(theta);
    return vec3(sin(phi) * s, cos(theta), -cos(phi) * s);
}

vec2 envmap_uv(vec3 d) {
    // atan(0, 0) is undefined in GLSL: the poles get u = 0. theta via atan (not acos, which is
    // far less accurate on some drivers).
    float u = (d.x == 0.0 && d.z == 0.0) ? 0.0 : atan(d.x, -d.z) * (0.5 * INV_PI);
    u = u < 0.0 ? u + 1.0 : u;
    return vec2(u >= 1.0 ? 0.0 : u, atan(length(d.xz), d.y) * INV_PI);
}

// Texel containing the local direction d (nearest filtering, matching the piecewise-constant
// pdf). GPU inverse trigonometry is loose (Vulkan allows 4096 ulp for atan; lavapipe's acos is
// off by ~1e-4), so the estimate from envmap_uv is snapped against the texel edges as the
// forward map envmap_direction places them (cos/sin), keeping envmap_pdf(envmap_sample(u)) and
// envmap_eval consistent with the texel that was sampled.
uvec2 envmap_texel(uvec2 size, vec3 d) {
    uvec2 t = min(uvec2(envmap_uv(d) * vec2(size)), size - 1u);
    // Row j holds cos(theta) in (cos(pi (j + 1) / H), cos(pi j / H)].
    if (t.y > 0u && d.y > cos(PI * (float(t.y) / float(size.y)))) t.y--;
    else if (t.y + 1u < size.y && d.y <= cos(PI * (float(t.y + 1u) / float(size.y)))) t.y++;
    // Column i holds phi in [phi_i, phi_i+1); sin(phi - phi_i) has the sign of
    // d.x cos(phi_i) + d.z sin(phi_i).
    float p0 = 2.0 * PI * (float(t.x) / float(size.x));
    float p1 = 2.0 * PI * (float(t.x + 1u) / float(size.x));
    if (d.x * cos(p0) + d.z * sin(p0) < 0.0) t.x = (t.x + size.x - 1u) % size.x;
    else if (d.x * cos(p1) + d.z * sin(p1) >= 0.0) t.x = (t.x + 1u) % size.x;
    return t;
}

// Largest i in [0, n) with cdf[i] <= u for the n + 1 CDF values at `offset`
// (cdf[0] = 0, cdf[n] = 1 > u): zero-probability bins are never returned.
uint envmap_find_interval(uint offset, uint n, float u) {
    uint lo = 0u, hi = n;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (envmap_data[offset + mid] <= u) lo = mid;
        else hi = mid;
    }
    return lo;
}

// Density over (u, v) of texel t (marginal x conditional).
float envmap_texel_pdf(uint record, uvec2 size, uvec2 t) {
    uint dist = record + envmap_u32(record + 3u);
    uint cond_pdf = dist + 2u * size.y + 1u;
    return envmap_data[dist + t.y] * envmap_data[cond_pdf + t.y * size.x + t.x];
}

// Solid-angle pdf of a local direction: pdf_uv / (2 pi^2 sin theta).
float envmap_pdf_local(uint record, uvec2 size, vec3 d) {
    float sin_theta = length(d.xz);
    if (sin_theta <= 0.0) return 0.0;
    return envmap_texel_pdf(record, size, envmap_texel(size, d)) / (2.0 * PI * PI * sin_theta);
}

// Solid-angle pdf of envmap_sample for a world direction.
float envmap_pdf(uint index, vec3 wi) {
    uint record = envmap_record(index);
    vec3 d = envmap_matrix(record + 16u) * wi;
    return envmap_pdf_local(record, envmap_size(index), normalize(d));
}

// Radiance towards -wi (wi: world direction from the scene to the environment), unscaled.
vec3 envmap_eval(uint index, vec3 wi) {
    uint record = envmap_record(index);
    uvec2 size = envmap_size(index);
    uvec2 t = envmap_texel(size, normalize(envmap_matrix(record + 16u) * wi));
    uint at = record + envmap_u32(record + 2u) + 3u * (t.y * size.x + t.x);
    return vec3(envmap_data[at], envmap_data[at + 1u], envmap_data[at + 2u]);
}

// World direction with density proportional to luminance; pdf in solid angle (0 = failed).
vec3 envmap_sample(uint index, vec2 u, out float pdf) {
    uint record = envmap_record(index);
    uvec2 size = envmap_size(index);
    uint dist = record + envmap_u32(record + 3u);
    uint marg_cdf = dist + size.y;
    uint cond_cdf = dist + 2u * size.y + 1u + size.x * size.y;
    // Row from the marginal, column from the row's conditional; linear within the bin.
    uint j = envmap_find_interval(marg_cdf, size.y, u.y);
    float c0 = envmap_data[marg_cdf + j], c1 = envmap_data[marg_cdf + j + 1u];
    float dv = clamp((u.y - c0) / (c1 - c0), 0.0, 1.0);
    uint row = cond_cdf + j * (size.x + 1u);
    uint i = envmap_find_interval(row, size.x, u.x);
    float d0 = envmap_data[row + i], d1 = envmap_data[row + i + 1u];
    float du = clamp((u.x - d0) / (d1 - d0), 0.0, 1.0);
    vec2 uv = (vec2(i, j) + vec2(du, dv)) / vec2(size);
    vec3 d = envmap_direction(uv);
    // Same sin(theta) expression as envmap_pdf_local: pdf(sample) == envmap_pdf(direction).
    float sin_theta = length(d.xz);
    float pdf_uv = envmap_texel_pdf(record, size, uvec2(i, j));
    pdf = sin_theta > 0.0 ? pdf_uv / (2.0 * PI * PI * sin_theta) : 0.0;
    return normalize(envmap_matrix(record + 4u) * d);
}

#endif
