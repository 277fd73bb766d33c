#!/usr/bin/env bash
# Where the path tracer's time goes on the current device (issue 22), measured by difference:
# llvmpipe's JIT code carries no symbols (perf attributes 91% of a PT render to "[JIT]"), so
# each stage is timed by running it twice per use and subtracting. A variant is the kernel with
# one call duplicated on inputs the compiler cannot prove equal (tmax 1e30 vs 2e30, a sample
# permuted) and the duplicate's result dropped by a test that never passes; control flow, path
# lengths and the image stay those of the base kernel. The marginal cost of the duplicate is
# the stage's cost, divergence included. A last variant writes, per pixel, the path loop's
# iterations and those of its SIMD batch (subgroupMax), giving the path loop's lane use.
# rng_x2 duplicates the light sample's random numbers: 2 of the 5 pcg4d hashes a vertex draws
# (light 2, BSDF 2, Russian roulette 1), so the RNG's whole cost is 2.5 times its marginal.
# Never asserts.
#
#   bash bench/profile_pt.sh                  # grey Cornell box, 128x128, 64 bounces
#   SCENE=bench/data/peer/glossy_env.json REPS=5 bash bench/profile_pt.sh
#
# Variants are perl substitutions on a copy of the shaders (LOOM_SHADER_PATH), each checked to
# apply exactly once, so a changed kernel makes this script fail instead of timing nothing.
source "$(dirname "$0")/lib.sh"
SCENE=${SCENE:-bench/data/peer/cornell_grey.json}
W=${WIDTH:-128} H=${HEIGHT:-128} FRAMES=${FRAMES:-33} REPS=${REPS:-3} BOUNCES=${BOUNCES:-64}
OUT=${OUT:-out/profile_pt}
mkdir -p "$OUT"
export LP_NUM_THREADS=${THREADS:-2}

PATH_GLSL=lib/integrator/path.glsl
# name|file|perl regex|replacement
VARIANTS=(
  "closest_x2|$PATH_GLSL|found = trace_closest\(st\.o, st\.d, 0\.0, 1e30, BVH_MASK_ALL, hit\);|{ Hit h2; bool f2 = trace_closest(st.o, st.d, 0.0, 2e30, BVH_MASK_ALL, h2); found = trace_closest(st.o, st.d, 0.0, 1e30, BVH_MASK_ALL, hit); if (f2 && h2.t < 0.0) { found = true; hit = h2; } }"
  "shadow_x2|$PATH_GLSL|if \(!trace_any\(shadow\.ray\.o, shadow\.ray\.d, 0\.0, shadow\.ray\.tmax, BVH_MASK_ALL\)\)|if ((uint(trace_any(shadow.ray.o, shadow.ray.d, 0.0, shadow.ray.tmax, BVH_MASK_ALL)) & (uint(trace_any(shadow.ray.o, shadow.ray.d, -1.0, shadow.ray.tmax, BVH_MASK_ALL)) | 1u)) == 0u)"
  "shading_x2|$PATH_GLSL|if \(found\) sh = shading_point\(hit\);|if (found) { Hit h3 = hit; h3.bary *= 0.999; ShadingPoint s3 = shading_point(h3); sh = shading_point(hit); if (s3.n.x > 2.0) sh = s3; }"
  "surface_x2|$PATH_GLSL|if \(found\) sh = shading_point\(hit\);|if (found) { SurfacePoint sp3 = surface_point(hit.prim, hit.bary * 0.999); sh = shading_point(hit); if (sp3.p.x > 1e30) sh.sp = sp3; }"
  "material_x2|$PATH_GLSL|if \(found\) sh = shading_point\(hit\);|if (found) { sh = shading_point(hit); Material m3 = scene_material(scene_shape(sh.sp.shape).material + (st.depth > 1000u ? 1u : 0u)); if (m3.diffuse.x < -1.0) sh.mat = m3; }"
  "nee_x2|$PATH_GLSL|NeeSample nee = nee_sample\(sh, wo, u_light, ps\.mis, ps\.mis_heuristic\);|NeeSample nee2 = nee_sample(sh, wo, u_light.yxz, ps.mis, ps.mis_heuristic); NeeSample nee = nee_sample(sh, wo, u_light, ps.mis, ps.mis_heuristic); if (nee2.value.x < -1.0) nee = nee2;"
  "bsdf_x2|$PATH_GLSL|BsdfSample bs = bsdf_sample\(sh\.mat, wo, u_bsdf\);|BsdfSample bs2 = bsdf_sample(sh.mat, wo, u_bsdf.yzx); BsdfSample bs = bsdf_sample(sh.mat, wo, u_bsdf); if (bs2.pdf < -1.0) bs = bs2;"
  "rng_x2|$PATH_GLSL|vec3 u_light = vec3\(rng_next2\(rng\), rng_next\(rng\)\);|Rng rng2 = rng; rng2.state.z ^= 0x9E3779B9u; vec3 u2 = vec3(rng_next2(rng2), rng_next(rng2)); vec3 u_light = vec3(rng_next2(rng), rng_next(rng)); if (u2.x < -1.0) u_light = u2;"
  "emission_x2|$PATH_GLSL|vec3 Le = emitter_hit_radiance\(st\.d, found, sh\);|vec3 Le = emitter_hit_radiance(st.d, found, sh); float lpdf2 = emitter_hit_light_pdf(st.prev_p, -st.d, found, hit.prim, sh); if (lpdf2 < -1.0) Le = vec3(lpdf2);"
)

make_variant() {  # name file regex replacement -> prints the shader dir
  local dir=$OUT/shaders-$1
  rm -rf "$dir" && mkdir -p "$dir/passes"
  cp -r shaders/lib "$dir/lib" && cp -r passes/path_tracer "$dir/passes/path_tracer"
  if [ -n "$2" ]; then
    local n
    n=$(RE="$3" REP="$4" perl -0pi -e '$n += s/$ENV{RE}/$ENV{REP}/g; END { print STDERR $n }' "$dir/$2" 2>&1)
    [ "$n" = 1 ] || { echo "profile_pt.sh: variant $1 matched $n times in $2 (kernel changed?)" >&2; exit 1; }
  fi
  echo "$dir"
}

counter_means() {  # shader dir, name, GLSL vec4 to store as the color -> its image mean "r g b"
  local dir=$1
  RE='(imageStore\(colorImage, ip,)[^;]*;' STORE="$3" perl -0pi -e \
    's/$ENV{RE}/$1 $ENV{STORE});/ or die "counters: store not found\n"' \
    "$dir/passes/path_tracer/path_tracer_common.glsl"
  LOOM_SHADER_PATH=$dir "$LOOM" render graphs/pt.json --scene "$SCENE" --width "$W" --height "$H" \
    --frames 4 --set pt.maxBounces="$BOUNCES" --quiet --output accum.output="$OUT/$2.exr" >"$OUT/$2.log" 2>&1 \
    || { echo "profile_pt.sh: $2 render failed: $(tail -3 "$OUT/$2.log")" >&2; exit 1; }
  echo 'local r, g, b = loom.read_image(loom.arg("image", "")):mean()
print(string.format("%.3f %.3f %.0f", r, g, b))' >"$OUT/means.lua"
  "$LOOM" run "$OUT/means.lua" image="$OUT/$2.exr"
}

pt_ms() {  # shader dir -> PT GPU ms per frame (loom --timings, first frame excluded)
  LOOM_SHADER_PATH=$1 "$LOOM" render graphs/pt.json --scene "$SCENE" --width "$W" --height "$H" \
    --frames "$FRAMES" --set pt.maxBounces="$BOUNCES" --timings --quiet --out "$OUT/last.exr" >"$OUT/last.log" 2>&1 \
    || { echo "profile_pt.sh: render failed: $(tail -3 "$OUT/last.log")" >&2; exit 1; }
  awk '$1 == "pt" && NF == 2 {print $2}' "$OUT/last.log"
}

declare -A dirs best
dirs[base]=$(make_variant base "" "" "")
names=(base)
for v in "${VARIANTS[@]}"; do
  IFS='|' read -r name file re rep <<<"$v"
  dirs[$name]=$(make_variant "$name" "$file" "$re" "$rep")
  names+=("$name")
done
echo "profile_pt: $SCENE, ${W}x${H}, $BOUNCES bounces, $FRAMES frames x $REPS interleaved reps (min); $(uptime)"
pt_ms "${dirs[base]}" >/dev/null  # compile the base kernel once; variants compile on first use
for ((r = 0; r < REPS; ++r)); do
  for n in "${names[@]}"; do
    ms=$(pt_ms "${dirs[$n]}")
    best[$n]=$(min_of "$ms" "${best[$n]:-}")
  done
done

# Lane use of the path loop: iterations per lane and per SIMD batch.
lanes=$OUT/shaders-lanes
make_variant lanes "" "" "" >/dev/null
RE='for \(;;\) \{' REP='for (;;) { ++prof_path_iters;' \
  perl -0pi -e 's/$ENV{RE}/$ENV{REP}/ or die "lanes: loop not found\n"' "$lanes/$PATH_GLSL"
RE='struct PathSettings \{' REP='uint prof_path_iters = 0u;
struct PathSettings {' perl -0pi -e 's/$ENV{RE}/$ENV{REP}/ or die "lanes: PathSettings not found\n"' "$lanes/$PATH_GLSL"
RE='(\#version 460\n)' perl -0pi -e 's/$ENV{RE}/$1#extension GL_KHR_shader_subgroup_arithmetic : require\n/ or die "lanes: version not found\n"' \
  "$lanes/passes/path_tracer/path_tracer.comp"
read -r lane_iters batch_iters subgroup < <(counter_means "$lanes" lanes \
  'vec4(float(prof_path_iters), float(subgroupMax(prof_path_iters)), float(gl_SubgroupSize), 1.0)')

# Lane use of BVH traversal: per query, the steps of this lane and the most steps of any lane of
# its SIMD batch (shared among the batch's active lanes, so that the image's sum is the batch's).
tlanes=$OUT/shaders-traversal-lanes
make_variant traversal-lanes "" "" "" >/dev/null
perl -0pi -e 's/(#define LOOM_BVH_GLSL\n)/$1#extension GL_KHR_shader_subgroup_arithmetic : require\nfloat prof_lane_steps = 0.0, prof_batch_share = 0.0;\n/ or die "traversal lanes: guard not found\n"' "$tlanes/lib/bvh.glsl"
perl -0pi -e '$n += s/(bool (trace_closest|trace_any)\([^)]*\) \{\n(    Hit hit;\n)?)    return (bvh_traverse\([^;]*\));/$1    uint prof_before = bvh_iterations;\n    bool prof_r = $4;\n    uint prof_steps = bvh_iterations - prof_before;\n    prof_lane_steps += float(prof_steps);\n    prof_batch_share += float(subgroupMax(prof_steps)) \/ float(subgroupAdd(1u));\n    return prof_r;/g; END { die "traversal lanes: trace functions not found\n" unless $n == 2 }' "$tlanes/lib/bvh.glsl"
read -r lane_steps batch_share _ < <(counter_means "$tlanes" traversal_lanes \
  'vec4(prof_lane_steps, prof_batch_share, 0.0, 1.0)')

base=${best[base]}
printf '\n| stage (duplicated) | PT GPU ms/frame | marginal ms | share of base |\n| --- | --- | --- | --- |\n'
printf '| base | %s | | |\n' "$base"
csv=$OUT/profile_pt.csv
echo "variant,pt_ms,marginal_ms,share" >"$csv"
for n in "${names[@]:1}"; do
  awk -v n="$n" -v t="${best[$n]}" -v b="$base" 'BEGIN { printf "| %s | %.2f | %.2f | %.0f%% |\n", n, t, t - b, 100 * (t - b) / b }'
  awk -v n="$n" -v t="${best[$n]}" -v b="$base" 'BEGIN { printf "%s,%.3f,%.3f,%.4f\n", n, t, t - b, (t - b) / b }' >>"$csv"
done
awk -v a="$lane_iters" -v m="$batch_iters" -v s="$subgroup" 'BEGIN {
  printf "\npath loop: %.2f iterations per path, %.2f per SIMD batch of %d lanes: lane use %.0f%%\n", a, m, s, 100 * a / m }'
awk -v a="$lane_steps" -v m="$batch_share" -v s="$subgroup" 'BEGIN {
  printf "BVH traversal: %.2f steps per path, %.2f per SIMD batch of %d lanes: lane use %.0f%% (of which the path loop'"'"'s is above)\n", a, m * s, s, 100 * a / (m * s) }'
echo "CSV: $csv"
