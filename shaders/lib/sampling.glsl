// Sampling routines shared by every estimator; each returns its pdf in the measure named.
#ifndef LOOM_SAMPLING_GLSL
#define LOOM_SAMPLING_GLSL

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;

// Duff et al. 2017, "Building an Orthonormal Basis, Revisited".
void orthonormal_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 to_world(vec3 v, vec3 n) {
    vec3 t, b;
    orthonormal_basis(n, t, b);
    return v.x * t + v.y * b + v.z * n;
}

// Shirley & Chiu 1997 concentric disk mapping.
vec2 sample_disk_concentric(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o == vec2(0.0)) return vec2(0.0);
    float r, theta;
    if (abs(o.x) > abs(o.y)) {
        r = o.x;
        theta = (PI / 4.0) * (o.y / o.x);
    } else {
        r = o.y;
        theta = PI / 2.0 - (PI / 4.0) * (o.x / o.y);
    }
    return r * vec2(cos(theta), sin(theta));
}

// Inverse of sample_disk_concentric: the u in [0,1)^2 that maps to p (|p| <= 1).
vec2 disk_concentric_inverse(vec2 p) {
    float r = length(p);
    if (r == 0.0) return vec2(0.5);
    float phi = atan(p.y, p.x);
    if (phi < -PI / 4.0) phi += 2.0 * PI;
    vec2 o;
    if (phi < PI / 4.0) o = vec2(r, r * phi * (4.0 / PI));
    else if (phi < 3.0 * PI / 4.0) o = vec2(r * (2.0 - phi * (4.0 / PI)), r);
    else if (phi < 5.0 * PI / 4.0) o = vec2(-r, -r * (phi - PI) * (4.0 / PI));
    else o = vec2(-r * (2.0 - (phi - PI) * (4.0 / PI)), -r);
    return clamp(0.5 * (o + 1.0), vec2(0.0), vec2(1.0 - 1e-7));
}

// Cosine-weighted hemisphere around +z; pdf = cos(theta) / pi (solid angle).
vec3 sample_cosine_hemisphere(vec2 u) {
    vec2 d = sample_disk_concentric(u);
    return vec3(d, sqrt(max(0.0, 1.0 - dot(d, d))));
}
float cosine_hemisphere_pdf(float cos_theta) { return max(cos_theta, 0.0) * INV_PI; }

vec3 sample_uniform_sphere(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// A point uniform by area on triangle (a, b, c) from u in [0, 1)^2 (square-root warp,
// pbrt-v4 SampleUniformTriangle up to the vertex order).
vec3 sample_triangle_point(vec2 u, vec3 a, vec3 b, vec3 c) {
    float su = sqrt(u.x);
    return (1.0 - su) * a + su * (1.0 - u.y) * b + su * u.y * c;
}

#endif
