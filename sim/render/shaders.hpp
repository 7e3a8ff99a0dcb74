// The renderer's GLSL sources (scene, sky, water; vertex and fragment), compiled by
// sim/render/renderer.cpp. Their bytes decide every rendered image: a change here changes the
// renders, and the byte-determinism and geometry tests say by how much.
#pragma once

namespace driftlab::sim::shaders {

// Shaders come in variants chosen by #defines: DEPTH (linear depth instead of
// gray), SUN (sun glints, which need per-pixel normals and view vectors), COLOUR (RGB
// images: the scene's materials tinted by their colour, water and sky gray), for the scene
// CUTOUT (an alpha-tested texture, grey in r and alpha in g: fragments under 0.5 are discarded in
// every pass, so the depth and mirror images show the same holes) and SWAY (the wind moves the
// vertices with sway weights; 0 for rigid meshes and still scenes, whose vertices the branch
// leaves where they are) and, for the sky, CLOUDS (the cloud deck's texture).
// On llvmpipe the cost of a fragment is mostly the interpolation of its
// inputs, so each variant carries only what it reads: lighting and fog are
// smooth over a triangle and are evaluated per vertex (Gouraud).
inline constexpr const char* kSceneVs = R"(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
#if SWAY
layout(location = 3) in vec2 a_sway;  // Mesh::sway: sway and flutter weights ((0, 0): rigid)
#endif
uniform mat4 u_view;       // world -> camera (optical)
uniform mat4 u_proj;
uniform mat4 u_model;      // mesh -> world: the identity, or the body's pose for a body mesh
uniform float u_mirror;    // 1: as is; -1: mirrored about the water plane z = 0
uniform vec3 u_sun_dir;    // towards the sun, world
uniform float u_ambient;
uniform float u_diffuse;
uniform float u_fog;
uniform vec3 u_eye;
// The wind in the vegetation (sim::VegetationSway at this pass's instant): a unit-weight vertex
// at distance s downwind moves by sum_k a_k sin(p_k - kappa_k s) along u_wind_dir, a leaf also
// by its flutter, downwind and half of it up or down.
uniform int u_sway_n;      // 0: nothing sways
uniform vec4 u_sway[8];    // a_k [m], kappa_k [rad/m], p_k [rad]
uniform vec2 u_wind_dir;
uniform vec2 u_flutter;    // amplitude [m], phase at this instant [rad]
uniform vec2 u_sway_reach; // the most a unit weight sways and flutters [m]
uniform float u_moving;    // 1 for a mover's mesh
#if SWAY
// 1: a moving thing: the green channel of the moving mask (the truth pass) and of the left
// eye's gray image (render_bands' moving_mask). Without sway it is u_moving (kSceneFs).
out float v_moving;
#endif
#if DEPTH
out float v_view_z;
#if CUTOUT
out vec2 v_uv;
#endif
#else
out vec4 v_uv_light_fog;   // texture u, v; light; fog transmittance
#endif
#if SUN && !DEPTH
out vec3 v_world;
out vec3 v_normal;
#endif
void main() {
  vec3 w = (u_model * vec4(a_pos, 1.0)).xyz;
  float moving = u_moving;
#if SWAY
  if (u_sway_n > 0 && a_sway != vec2(0.0)) {
    float s = dot(u_wind_dir, w.xy), g = 0.0;
    for (int k = 0; k < u_sway_n; ++k) g += u_sway[k].x * sin(u_sway[k].z - u_sway[k].y * s);
    float f = u_flutter.x * sin(u_flutter.y + 37.0 * w.x + 91.0 * w.y + 53.0 * w.z);
    w += vec3(u_wind_dir * (a_sway.x * g + a_sway.y * f), 0.5 * a_sway.y * f);
    if (dot(a_sway, u_sway_reach) > 0.001) moving = 1.0;  // it moves by a millimetre or more
  }
#endif
  vec3 p = vec3(w.xy, w.z * u_mirror);
  vec4 c = u_view * vec4(p, 1.0);
#if SWAY
  v_moving = moving;
#endif
#if DEPTH
  v_view_z = c.z;
#if CUTOUT
  v_uv = a_uv;
#endif
#else
  vec3 m = mat3(u_model) * a_normal;
  vec3 n = normalize(vec3(m.xy, m.z * u_mirror));
  // Overcast light comes mostly from above (-z); the sun adds a directional term.
  // Surfaces facing down still get light bounced from the water and ground.
  float sky_light = mix(0.35, 1.0, 0.5 + 0.5 * clamp(-n.z, -1.0, 1.0));
#if SUN
  float light = u_ambient * sky_light + u_diffuse * max(dot(n, u_sun_dir), 0.0);
  v_world = p;
  v_normal = n;
#else
  float light = u_ambient * sky_light + u_diffuse * 0.6 * sky_light;
#endif
  v_uv_light_fog = vec4(a_uv, light, exp(-length(u_eye - p) / u_fog));
#endif
  // Mirrored pass: keep only what is above the water (z < 0 before mirroring).
  gl_ClipDistance[0] = u_mirror < 0.0 ? -w.z : 1.0;
  gl_Position = u_proj * c;
}
)";

inline constexpr const char* kSceneFs = R"(
#if DEPTH
in float v_view_z;
#if CUTOUT
in vec2 v_uv;
#endif
#else
in vec4 v_uv_light_fog;
#endif
#if SUN && !DEPTH
in vec3 v_world;
in vec3 v_normal;
#endif
uniform sampler2D u_tex;
uniform bool u_has_tex;
uniform float u_albedo;
uniform float u_specular;
uniform vec3 u_tint;       // the material's colour (COLOUR images only)
uniform vec3 u_sun_dir;
uniform float u_sky;
uniform vec3 u_eye;
#if SWAY
in float v_moving;
#else
uniform float u_moving;
#define v_moving u_moving
#endif
out vec4 frag;
void main() {
#if DEPTH
#if CUTOUT
  if (texture(u_tex, v_uv).g < 0.5) discard;
#endif
  frag = vec4(v_view_z, v_moving > 0.5 ? 1.0 : 0.0, 0.0, 1.0);
#else
#if CUTOUT
  vec2 ta = texture(u_tex, v_uv_light_fog.xy).rg;
  if (ta.g < 0.5) discard;
  float t = ta.r;
#else
  float t = u_has_tex ? texture(u_tex, v_uv_light_fog.xy).r : 1.0;
#endif
  float g = u_albedo * t * v_uv_light_fog.z;
#if SUN
  if (u_specular > 0.0) {
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_eye - v_world);
    vec3 h = normalize(v + u_sun_dir);
    g += u_specular * pow(max(dot(n, h), 0.0), 60.0);
  }
#endif
#if COLOUR
  frag = vec4(mix(vec3(u_sky), g * u_tint, v_uv_light_fog.w), 1.0);
#else
  frag = vec4(mix(u_sky, g, v_uv_light_fog.w), v_moving > 0.5 ? 1.0 : 0.0, 0.0, 1.0);
#endif
#endif
}
)";

// The sky: one triangle over the screen on the far plane. The (unnormalised)
// viewing ray is affine in window coordinates, so it is computed at the
// vertices and interpolated without perspective: exact, and cheap per pixel.
// In the mirror pass (u_mirror -1) a pixel shows the sky in the mirrored
// direction, and only where its ray looks down: the clip distance is the ray's
// z, affine over the screen like the ray, so the horizon is cut exactly.
inline constexpr const char* kSkyVs = R"(
uniform mat4 u_inv_view_proj;
uniform float u_mirror;
noperspective out vec3 v_ray;
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  vec4 a = u_inv_view_proj * vec4(p, -1.0, 1.0);
  vec4 b = u_inv_view_proj * vec4(p, 1.0, 1.0);
  v_ray = b.xyz / b.w - a.xyz / a.w;
  gl_ClipDistance[0] = u_mirror < 0.0 ? v_ray.z : 1.0;
  gl_Position = vec4(p, 1.0, 1.0);
}
)";

// The sky's luminance (Lighting): the gradient L_h (1 + (r - 1) sin e), the
// cloud deck at height H read where the ray meets it (d.xy H / sin e, in
// tiles), its contrast faded along the slant path, then the highlight shoulder.
inline constexpr const char* kSkyFs = R"(
noperspective in vec3 v_ray;
uniform float u_sky;       // L_h: the horizon's luminance before the shoulder
uniform float u_gradient;  // r - 1
uniform float u_knee;      // >= 1: clip at 1
uniform float u_mirror;
#if CLOUDS
uniform sampler2D u_clouds;  // n as 128 + 32 n
uniform float u_cloud_scale; // H / tile
uniform float u_cloud_gain;  // contrast 255 / 32
uniform float u_cloud_haze;  // H / visibility
#endif
#if SUN
uniform vec3 u_sun_dir;
uniform float u_halo;
#endif
out vec4 frag;
void main() {
  vec3 d = normalize(v_ray * vec3(1.0, 1.0, u_mirror));
  float s = clamp(-d.z, 0.0, 1.0);   // sin(elevation); z is down
  float g = u_sky * (1.0 + u_gradient * s);
#if CLOUDS
  float inv_s = 1.0 / max(s, 1e-3);
  float n = texture(u_clouds, d.xy * (u_cloud_scale * inv_s)).r - 128.0 / 255.0;
  g *= 1.0 + u_cloud_gain * n * exp(-u_cloud_haze * inv_s);
#endif
#if SUN
  g += u_halo * pow(max(dot(d, u_sun_dir), 0.0), 200.0);
#endif
  if (u_knee < 1.0 && g > u_knee)
    g = u_knee + (1.0 - u_knee) * (1.0 - exp((u_knee - g) / (1.0 - u_knee)));
#if COLOUR
  frag = vec4(vec3(min(g, 1.0)), 1.0);
#else
  frag = vec4(min(g, 1.0), 0.0, 0.0, 1.0);
#endif
}
)";

// The wave components (sim/physics/waves/wave_field.hpp), shared by the water's two stages: the
// vertex stage displaces the grid with them, the fragment stage takes its normal from them.
inline constexpr const char* kWaterWaves = R"(
const int N = 32;
uniform vec4 u_wave_a[N];   // amplitude, kx, ky, omega
uniform float u_wave_phase[N];
uniform int u_wave_count;
uniform float u_time;
// The waves' height eta (z) and slope grad eta (xy) at xy, as a sampler with steps d1 and d2
// [m] can carry them (the grid's spacing at a vertex, a pixel's footprint on the water): the
// field low-passed by a Gaussian of standard deviation |d| / 2 along each step, so a
// component of wavevector k keeps exp(-((k.d1)^2 + (k.d2)^2) / 8) of its amplitude (0.29 at
// the Nyquist wavelength, k.d = pi; 0.007 at the step itself) instead of aliasing.
// `unresolved`: the slope variance so left out, sum of (1 - g^2) a^2 |k|^2 / 2.
vec3 waves(vec2 xy, vec2 d1, vec2 d2, out float unresolved) {
  vec3 s = vec3(0.0);
  unresolved = 0.0;
  for (int i = 0; i < u_wave_count; ++i) {
    vec2 k = u_wave_a[i].yz;
    float q1 = dot(k, d1), q2 = dot(k, d2);
    float g = exp(-0.125 * (q1 * q1 + q2 * q2));
    float a = u_wave_a[i].x;
    float th = dot(k, xy) - u_wave_a[i].w * u_time + u_wave_phase[i];
    s.z += g * a * cos(th);
    s.xy -= g * a * sin(th) * k;
    unresolved += (1.0 - g * g) * 0.5 * a * a * dot(k, k);
  }
  return s;
}
)";

// The water: a polar grid around the camera displaced by the wave components it can carry
// (eta positive up, surface at z = -eta; kWaterWaves). Normals, and with them the Fresnel
// reflectance, the reflection's offset and the sun's glint, are the fragment stage's, from
// the waves at each pixel: what the camera sees of the water comes from the waves, not from
// the mesh.
inline constexpr const char* kWaterVs = R"(
layout(location = 0) in vec2 a_grid;       // offset from the camera, world x/y
uniform vec2 u_grid_step;   // the grid's spacing over its radius: radial, tangential
uniform vec2 u_centre;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform vec3 u_eye;
uniform float u_fog;
#if DEPTH
out float v_view_z;
#else
out float v_fog;
out vec3 v_world;
#endif
#if RIPPLES && !DEPTH
uniform vec2 u_focal;       // fx, fy [px]
out vec4 v_jacobian;       // d(mirror pixel)/d(slope), columns (x, y) [px]
// Pixel position of the reflection, in the mirror image, of the ray d from the
// eye reflected off a surface of slope s (grad eta).
vec2 mirror_px(vec3 d, vec2 s) {
  vec3 r = mat3(u_view) * reflect(d, normalize(vec3(-s, -1.0)));
  return u_focal * r.xy / max(r.z, 0.05);
}
#endif
void main() {
  vec2 xy = u_centre + a_grid;
  float r = length(a_grid);
  vec2 radial = r > 0.0 ? a_grid / r : vec2(1.0, 0.0);
  float unresolved;
  float eta = waves(xy, radial * (r * u_grid_step.x), vec2(-radial.y, radial.x) * (r * u_grid_step.y),
                    unresolved).z;
  vec3 p = vec3(xy, -eta);
  vec4 c = u_view * vec4(p, 1.0);
#if DEPTH
  v_view_z = c.z;
#else
  v_fog = exp(-length(u_eye - p) / u_fog);
  v_world = p;
#if RIPPLES
  // The Jacobian of the mirror pixel in the ripple slope at the flat surface:
  // smooth over the water, so taken once per vertex (central differences).
  vec3 d = normalize(p - u_eye);
  const float eps = 0.01;
  v_jacobian = vec4(mirror_px(d, vec2(eps, 0.0)) - mirror_px(d, vec2(-eps, 0.0)),
                    mirror_px(d, vec2(0.0, eps)) - mirror_px(d, vec2(0.0, -eps))) / (2.0 * eps);
#endif
#endif
  gl_Position = u_proj * c;
}
)";

inline constexpr const char* kWaterFs = R"(
#if DEPTH
in float v_view_z;
#else
in float v_fog;
in vec3 v_world;
#endif
#if RIPPLES && !DEPTH
in vec4 v_jacobian;
#endif
// Wind ripples (sim/physics/waves/ripple_spectrum.hpp): two repeating tiles of slope
// moments (sx, sy, sx^2, sy^2), each with its inverse size [1/m] and the eye's
// position in it (in tiles, reduced on the CPU in double).
uniform sampler2D u_ripple_map0;
uniform sampler2D u_ripple_map1;
uniform float u_ripple_inv_size0;
uniform float u_ripple_inv_size1;
uniform vec2 u_ripple_offset0;
uniform vec2 u_ripple_offset1;
uniform mat4 u_view;
uniform vec2 u_focal;           // fx, fy [px]
uniform float u_refl_max_lod;
uniform float u_refl_texel_px;  // image pixels per texel of the reflection pass (geometric mean)
uniform vec3 u_eye;
uniform sampler2D u_reflection;
uniform bool u_has_reflection;
uniform vec2 u_viewport;
uniform float u_shift_max;      // bound on the waves' tilt of the lookup [uv]
uniform float u_body;
uniform float u_turbidity;
uniform float u_reflectivity;
uniform float u_sky;
uniform vec3 u_sun_dir;
out vec4 frag;
#if RIPPLES && !DEPTH
// Pixel position of the reflection in the mirror image of the ray from the
// eye to this fragment, reflected off a surface of slope s (grad eta).
vec2 mirror_px(vec2 s) {
  vec3 d = normalize(v_world - u_eye);
  vec3 r = mat3(u_view) * reflect(d, normalize(vec3(-s, -1.0)));
  return u_focal * r.xy / max(r.z, 0.05);
}
#endif
void main() {
#if DEPTH
  frag = vec4(v_view_z, 0.0, 0.0, 1.0);
#else
  // The waves at this pixel, low-passed by its footprint on the water.
  float waves_unresolved;
  vec2 slope_w = waves(v_world.xy, dFdx(v_world.xy), dFdy(v_world.xy), waves_unresolved).xy;
  vec3 n = normalize(vec3(-slope_w, -1.0));   // upward normal (z is down)
  vec3 v = normalize(u_eye - v_world);
  float cos_t = clamp(dot(n, v), 0.0, 1.0);
  // Schlick's approximation of the Fresnel reflectance of water (n = 1.33).
  float m = 1.0 - cos_t, m2 = m * m;
  float fresnel = (0.02 + 0.98 * m2 * m2 * m) * u_reflectivity * (1.0 - 0.5 * u_turbidity);
  float refl = u_sky;
  if (u_has_reflection) {
    // The waves' normal tilts the lookup by at most u_shift_max (their slope bound): the band
    // of the mirror image a rolling-shutter band draws holds every row it reads.
    vec2 uv = gl_FragCoord.xy / u_viewport
            + clamp(0.15 * n.xy, -u_shift_max, u_shift_max) * vec2(1.0, -1.0);
#if RIPPLES
    // Wind ripples: the mip-mapped moments averaged over this pixel's
    // footprint. Their mean slope tilts the reflected ray; their variance
    // less the square of the mean is the slope variance of the ripples the
    // footprint averages away, which blurs the reflection instead, as a rough
    // mirror does (LEAN mapping, Olano and Baker 2010).
    vec2 rel = v_world.xy - u_eye.xy;
    vec4 m0 = texture(u_ripple_map0, rel * u_ripple_inv_size0 + u_ripple_offset0);
    vec4 m1 = texture(u_ripple_map1, rel * u_ripple_inv_size1 + u_ripple_offset1);
    vec2 slope = m0.xy + m1.xy;
    float unresolved = max(m0.z + m0.w - dot(m0.xy, m0.xy), 0.0)
                     + max(m1.z + m1.w - dot(m1.xy, m1.xy), 0.0) + waves_unresolved;
    // Where the reflected ray through the rippled surface lands in the
    // mirror image, against the ray through the flat surface: exact for
    // the reflection of distant objects.
    vec2 p0 = mirror_px(vec2(0.0)), p1 = mirror_px(slope);
    uv += (p1 - p0) / u_viewport;
    // The unresolved ripples spread the reflected rays: the spread of their
    // image is J S J^T, J the Jacobian of mirror_px in the slope (at the
    // flat surface, from the vertex shader) and S the slope covariance
    // (isotropic). At grazing angles it is long and
    // vertical (the streaks of a rippled reflection): the long axis is
    // sampled in five taps, the short one by the mip level.
    mat2 J = mat2(v_jacobian.xy, v_jacobian.zw);
    mat2 C = 0.5 * unresolved * J * transpose(J);
    float half_tr = 0.5 * (C[0][0] + C[1][1]);
    float det = C[0][0] * C[1][1] - C[0][1] * C[1][0];
    float root = sqrt(max(half_tr * half_tr - det, 0.0));
    float major = sqrt(half_tr + root), minor = sqrt(max(half_tr - root, 0.0));
    vec2 axis = abs(C[1][0]) > 1e-9 ? normalize(vec2(half_tr + root - C[1][1], C[1][0]))
                                    : (C[0][0] >= C[1][1] ? vec2(1.0, 0.0) : vec2(0.0, 1.0));
    // A mip level of width w texels (w u_refl_texel_px pixels) has a
    // standard deviation of about w / 2.5 texels.
    float lod = clamp(log2(max(2.5 * minor / u_refl_texel_px, 1.0)), 0.0, u_refl_max_lod);
    vec2 step = axis * (major / 0.866) / u_viewport;  // taps -2..2 at 0.75 step: sd 0.866
    const float w[5] = float[5](1.0, 2.0, 3.0, 2.0, 1.0);
    float sum = 0.0;
    for (int j = 0; j < 5; ++j)
      sum += w[j] * textureLod(u_reflection, clamp(uv + (0.75 * float(j - 2)) * step,
                                                   vec2(0.0), vec2(1.0)), lod).r;
    refl = sum / 9.0;
#else
    refl = texture(u_reflection, clamp(uv, vec2(0.0), vec2(1.0))).r;
#endif
  }
  float body = u_body * (0.6 + 0.8 * u_turbidity);
  float g = mix(body, refl, fresnel);
#if SUN
  vec3 r = reflect(-v, n);
  g += 0.8 * pow(max(dot(r, u_sun_dir), 0.0), 300.0);
#endif
#if COLOUR
  frag = vec4(vec3(mix(u_sky, g, v_fog)), 1.0);
#else
  frag = vec4(mix(u_sky, g, v_fog), 0.0, 0.0, 1.0);
#endif
#endif
}
)";

// One mip level of the mirror image from the level above (sim/render/mip_chain.hpp): a
// triangle over the level, each texel the mean of the 2x2 texels above it.
inline constexpr const char* kMipVs = R"(
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

inline constexpr const char* kMipFs = R"(
uniform sampler2D u_src;   // its base and max level: the level above
out vec4 frag;
void main() {
  ivec2 last = textureSize(u_src, 0) - 1;
  ivec2 p = 2 * ivec2(gl_FragCoord.xy);
  float s = texelFetch(u_src, min(p, last), 0).r + texelFetch(u_src, min(p + ivec2(1, 0), last), 0).r
          + texelFetch(u_src, min(p + ivec2(0, 1), last), 0).r
          + texelFetch(u_src, min(p + ivec2(1, 1), last), 0).r;
  frag = vec4(0.25 * s, 0.0, 0.0, 1.0);
}
)";

}  // namespace driftlab::sim::shaders
