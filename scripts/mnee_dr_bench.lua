-- MNEE with dimension reduction (Granizo-Hidalgo & Holzschuch 2024) on the animated pool
-- (scenes/water_pool_animated.json): run by bench/mnee_dr.sh, which documents the arguments.
--
-- 1. Time per frame against the water's tessellation (paper Fig. 11/12): per heightfield
--    resolution n (2 n^2 triangles), GPU ms per frame of graphs/mnee_dr.json with the water
--    animated (re-tessellated every frame), of graphs/pt.json on the same frames (the frame
--    without the caustic), their difference (the caustic part), and the scene update's CPU ms
--    (re-tessellation, BVH, of which the triangle adjacency).
-- 2. Equal quality against biased SMS (paper Sec. 6: about 6x at about 20 solutions per
--    sample, CPU): the pool from under water (SMS runs at primary receivers), frame time 0, the
--    caustic after `frames` frames against an unbiased-SMS reference; biased SMS with M trials
--    per sample for each M; where its RMSE reaches MNEE's, the ratio of GPU ms per frame. Once
--    per wave height scale (eq_height_scales: the scene's waves, and steeper ones where SMS's
--    walks converge less often).
local util = require("util")

local scene = util.resolve(loom.arg("scene", "scenes/water_pool_animated.json"))
local out = loom.arg("out", "out/mnee_dr")
local W, H = loom.arg("width", 960), loom.arg("height", 720)
local resolutions = loom.arg("resolutions", {7, 22, 71, 224, 707, 1000})
local frames = loom.arg("frames", 3)
local eqW, eqH = loom.arg("eq_width", 160), loom.arg("eq_height", 120)
local eqFrames = loom.arg("eq_frames", 16)
local refFrames = loom.arg("ref_frames", 256)
local trials = loom.arg("trials", {1, 2, 4, 8, 16, 32})
local eqResolution = loom.arg("eq_resolution", 128)
local eqHeightScales = loom.arg("eq_height_scales", {1, 4})

-- The scene with the water at resolution n (2 n^2 triangles) and its waves scaled.
local function scene_with(n, height_scale)
  local s = loom.read_json(scene)
  for _, shape in ipairs(s.shapes) do
    if shape.type == "heightfield" then
      shape.resolution = n
      shape.height_scale = height_scale or 1
    end
  end
  local copy = string.format("%s/scene_n%d_h%s.json", out, n, tostring(height_scale or 1))
  loom.write_json(copy, s)
  return copy
end

print(string.format("== 1. time per frame vs tessellation, %dx%d, %d animated frames each", W, H,
                    frames))
local rows = {}
for i, n in ipairs(resolutions) do
  local file = scene_with(n)
  local r = loom.renderer{graph = "graphs/mnee_dr.json", scene = file, width = W, height = H}
  local c, st = util.animated_costs(r, frames)
  r:close()
  local p = loom.renderer{graph = "graphs/pt.json", scene = file, width = W, height = H}
  local pt_ms = util.animated_costs(p, frames).gpu_ms
  p:close()
  rows[#rows + 1] = {water_triangles = 2 * n * n, frame_ms = c.gpu_ms, pt_ms = pt_ms,
                     caustic_ms = c.gpu_ms - pt_ms, update_ms = c.update_ms,
                     adjacency_ms = c.adjacency_ms,
                     triangles_per_walk = st["mnee.trianglesPerWalk"],
                     success = st["mnee.successRate"], walks = st["mnee.walks"]}
  loom.progress(i, #resolutions, "tessellation")
end
util.print_table({{key = "water_triangles", title = "water triangles"},
                  {key = "frame_ms", title = "frame GPU ms", fmt = "%.0f"},
                  {key = "pt_ms", title = "without caustic", fmt = "%.0f"},
                  {key = "caustic_ms", title = "caustic ms", fmt = "%.0f"},
                  {key = "update_ms", title = "scene update CPU ms", fmt = "%.1f"},
                  {key = "adjacency_ms", title = "adjacency CPU ms", fmt = "%.2f"},
                  {key = "triangles_per_walk", title = "triangles/walk", fmt = "%.2f"},
                  {key = "success", title = "walks solved", fmt = "%.3f"}}, rows)
loom.write_csv(out .. "/tessellation.csv", rows)

local function equal_quality(height_scale)
  print(string.format("== 2. equal quality vs biased SMS, %dx%d, %d frames, from under water, n = %d, "
                      .. "waves x %s", eqW, eqH, eqFrames, eqResolution, tostring(height_scale)))
  local eqScene = scene_with(eqResolution, height_scale)
  local tag = "h" .. tostring(height_scale)
  local underwater = {origin = {0.2, 0.45, 0.85}, target = {-0.2, 0.1, -0.6}, up = {0, 1, 0}, fov = 60}
  local function caustic(graph, params, n)
    local r = loom.renderer{graph = graph, scene = eqScene, width = eqW, height = eqH,
                            params = params}
    r:camera(underwater)
    r:set_time(0)
    local gpu = 0
    for _ = 1, n do
      r:frame()
      gpu = gpu + r:timings().frame_ms
    end
    local img = r:image("accumCaustic.output")
    local st = r:stats()
    r:close()
    return img, gpu / n, st
  end
  -- Every method at receiverDepth 0 (receivers seen directly), as passes/mnee_dr/README.md's
  -- table was measured.
  local ref = caustic("graphs/sms.json", {["sms.maxChain"] = 1, ["sms.receiverDepth"] = 0},
                      refFrames)
  ref:write(string.format("%s/%s_reference_caustic.exr", out, tag))
  local eq = {}
  local function measure(name, graph, params, m)
    local img, ms = caustic(graph, params, eqFrames)
    img:write(string.format("%s/%s_%s.exr", out, tag, name))
    local rmse = loom.metrics.rmse(img, ref)
    local rr, rg, rb = ref:mean()
    local ir, ig, ib = img:mean()
    eq[#eq + 1] = {waves = height_scale, method = name, M = m, rmse = rmse, relmse = loom.metrics.relmse(img, ref),
                   ms_per_frame = ms, energy = (ir + ig + ib) / (rr + rg + rb)}
  end
  measure("mnee_dr", "graphs/mnee_dr.json", {["mnee.receiverDepth"] = 0}, 1)
  for _, m in ipairs(trials) do
    measure("biased_sms_M" .. m, "graphs/sms_biased.json",
            {["sms.maxChain"] = 1, ["sms.biasedTrials"] = m, ["sms.receiverDepth"] = 0}, m)
  end
  util.print_table({{key = "method"}, {key = "M"}, {key = "rmse", fmt = "%.5f"},
                    {key = "relmse", fmt = "%.5f"}, {key = "energy", title = "energy vs ref",
                    fmt = "%.4f"}, {key = "ms_per_frame", title = "GPU ms/frame", fmt = "%.1f"}}, eq)
  loom.write_csv(string.format("%s/equal_quality_%s.csv", out, tag), eq)
  -- The smallest M whose RMSE reaches MNEE's (interpolated in log M between its neighbours).
  local dr = eq[1]
  local found = false
  for i = 2, #eq do
    if eq[i].rmse <= dr.rmse then
      local ms = eq[i].ms_per_frame
      if i > 2 then
        local a, b = eq[i - 1], eq[i]
        local w = (a.rmse - dr.rmse) / (a.rmse - b.rmse)
        ms = math.exp((1 - w) * math.log(a.ms_per_frame) + w * math.log(b.ms_per_frame))
      end
      print(string.format("biased SMS reaches MNEE's RMSE %.5f at M = %d (M* ~ %.1f): %.1f vs %.1f ms "
                          .. "per frame, MNEE with dimension reduction %.1fx faster", dr.rmse, eq[i].M,
                          i > 2 and math.exp((1 - (eq[i - 1].rmse - dr.rmse) / (eq[i - 1].rmse -
                          eq[i].rmse)) * math.log(eq[i - 1].M) + (eq[i - 1].rmse - dr.rmse) /
                          (eq[i - 1].rmse - eq[i].rmse) * math.log(eq[i].M)) or eq[i].M, ms,
                          dr.ms_per_frame, ms / dr.ms_per_frame))
      found = true
      break
    end
  end
  if not found then
    local last = eq[#eq]
    print(string.format("biased SMS does not reach MNEE's RMSE %.5f up to M = %d (%.5f there): at "
                        .. "least %.1fx faster", dr.rmse, last.M, last.rmse,
                        last.ms_per_frame / dr.ms_per_frame))
  end
end

for _, h in ipairs(eqHeightScales) do equal_quality(h) end
