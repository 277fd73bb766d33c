-- restir_equal_time.lua: render graphs compared at equal GPU time against a PT reference,
-- with a static camera (converging), a still one and a moving one (single frames). Default:
-- PT (graphs/pt.json) vs ReSTIR PT (graphs/restir_pt.json) on scenes/glossy_spheres.json and,
-- when present, ../shared/scenes/veach-ajar/scene.xml.
--
--   loom run scripts/restir_equal_time.lua [width=128 height=128 budget_ms=4000 steps=5 ...]
--   loom run scripts/restir_equal_time.lua configs=my_configs.json scenes=scenes/cornell_box.json
--
-- Configurations are {name, graph, params, spp_param}: any graph whose `output` port (default
-- accum.output) accumulates the estimate. configs=FILE.json replaces the default list with
-- [{"name": .., "graph": .., "params": {..}, "spp_param": ..}, ...].
--
-- static: the scene camera never moves. Each configuration renders until the summed GPU frame
--   times reach budget_ms * 2^(k - steps), k = 1..steps (r:run_for_ms), and the accumulated
--   image is compared with the reference at every step (relMSE, MAPE): a convergence curve.
--   Accumulated ReSTIR frames are correlated (they share reservoirs) but the estimator stays
--   consistent, so the curve still falls towards 0, only more slowly than 1/t.
-- moving: the camera swings `move_degrees` about its target over `move_frames` frames
--   (r:camera_path + r:set_time, one time step per frame) and ends on the scene camera, so the
--   same reference applies to the last frame. Accumulation restarts every frame while the
--   camera moves, so the last frame is a single-frame estimate (ReSTIR PT with the history it
--   gathered while moving). Equal time per frame: the configurations without `spp_param` run
--   first; one with `spp_param` sets it so that its frame time (calibrated on a few frames)
--   matches the slowest of those. relMSE/MAPE of the last frame are averaged over `repeats`
--   seeds (r:set_seed + r:reset, one renderer per configuration).
-- still: as moving, with the camera at rest (a scene's own camera path is replaced by its time-0
--   pose): the last of move_frames frames, single-frame
--   estimates at equal time per frame (how Lin et al. 2022 compare ReSTIR PT with PT).
-- Metrics: relMSE, MSE and MAPE (loom.metrics, eps 0.01), and for still/moving rows HDR-FLIP
-- (loom.metrics.flip, mean over the pixels) and relMSE without the worst `trim`
-- (default 0.001) of the pixels: fireflies dominate relMSE in scenes like veach-ajar.
-- Still/moving rows also give the standard error of relMSE and MSE over the repeats (fireflies make it
-- large: same-estimator rows can differ 3x at 8 repeats), the ratio at equal time with the
-- first configuration's relMSE scaled by frame time (spp_param is an integer: its frame time
-- can miss the target by a fraction of a sample), the rays traced per frame (every pass's `rays` stat) and the
-- ratio at equal rays: the first configuration's relMSE scaled to the samples per pixel this
-- one's rays would buy (relMSE ~ 1/spp), a proxy for GPU time where BVH traversal dominates.
--
-- Arguments: scenes (comma list; missing files are skipped), cameras (static,still,moving), width,
-- height, budget_ms, steps, move_frames, move_degrees, move (swing, dolly), move_dolly, move_end,
-- move_zoom, shutter, repeats, seed, ref_frames, ref_spp,
-- ref_bounces (the estimators' maxBounces, 9), trim, configs, out. Scenes are looked up as
-- given, then in the Loom source tree (so ../shared/scenes/... works from the repository root).
-- Writes OUT/restir_equal_time.csv (every step), OUT/<scene>_static.png/.svg (relMSE vs GPU
-- time), OUT/<scene>_<config>_<camera>.png (final images), and prints the tables.
local util = require("util")

local width, height = loom.arg("width", 128), loom.arg("height", 128)
local budget = loom.arg("budget_ms", 4000.0)
local steps = loom.arg("steps", 5)
local move_frames = loom.arg("move_frames", 16)
local move_degrees = loom.arg("move_degrees", 10.0)
-- swing: rotate about the target; dolly: also move in towards the target (the last
-- move_dolly of the distance, forward motion opens holes) and zoom in (fov from move_zoom x fov).
local move = loom.arg("move", "swing")
local move_dolly, move_zoom = loom.arg("move_dolly", 0.15), loom.arg("move_zoom", 1.15)
-- move_end = scene: every move ends on the scene camera (the reference's pose). ahead: the move
-- starts at the scene camera and ends move_dolly of the way to its target, where the reference,
-- the static and the still renderers look from too: forward motion in scenes with a wall right
-- behind the camera (the staircase).
local move_end = loom.arg("move_end", "scene")
if move_end ~= "scene" and move_end ~= "ahead" then error("move_end: expected scene or ahead") end
local end_pose = nil  -- per scene, with move_end = ahead
-- shutter=OPEN,CLOSE (frames): every renderer's camera shutter, and a reference that samples it
-- (PathTracer's motionBlur, on by default): for estimators with motion blur.
local shutter = loom.arg("shutter", {})
if #shutter ~= 0 and #shutter ~= 2 then error("shutter: expected OPEN,CLOSE") end
if #shutter == 0 then shutter = nil else shutter = {tonumber(shutter[1]), tonumber(shutter[2])} end
local repeats = loom.arg("repeats", 2)
local seed = loom.arg("seed", 1)
local out = loom.arg("out", "out/restir_equal_time")
local cameras = loom.arg("cameras", {"static", "still", "moving"})
local scenes = loom.arg("scenes", {"scenes/glossy_spheres.json",
                                   "../shared/scenes/veach-ajar/scene.xml"})
local ref_frames, ref_spp = loom.arg("ref_frames", 16), loom.arg("ref_spp", 64)
local ref_bounces = loom.arg("ref_bounces", 9)

local configs = {
  {name = "PT", graph = "graphs/pt.json", params = {}, spp_param = "pt.samplesPerPixel"},
  {name = "ReSTIR PT", graph = "graphs/restir_pt.json", params = {}},
}
local configs_file = loom.arg("configs", "")
if configs_file ~= "" then configs = loom.read_json(configs_file) end

local resolve, stem_of = util.resolve, util.stem_of

-- relMSE without the worst `frac` of the pixels (per-pixel relMSE, loom.metrics' eps = 0.01):
-- fireflies dominate relMSE in scenes like veach-ajar; this shows the error of the rest.
local function trimmed_relmse(img, ref, frac)
  local errs, w, h = {}, ref:width(), ref:height()
  for y = 0, h - 1 do
    for x = 0, w - 1 do
      local a1, a2, a3 = img:get(x, y)
      local b1, b2, b3 = ref:get(x, y)
      errs[#errs + 1] = ((a1 - b1) ^ 2 / (b1 ^ 2 + 0.01) + (a2 - b2) ^ 2 / (b2 ^ 2 + 0.01)
                         + (a3 - b3) ^ 2 / (b3 ^ 2 + 0.01)) / 3
    end
  end
  table.sort(errs)
  local keep = #errs - math.floor(#errs * frac)
  local sum = 0
  for i = 1, keep do sum = sum + errs[i] end
  return sum / keep
end
local trim = loom.arg("trim", 0.001)
local function slug(s) return (s:gsub("[^%w]+", "_")) end

local function renderer(cfg, scene, extra)
  local params = {}
  for k, v in pairs(cfg.params or {}) do params[k] = v end
  for k, v in pairs(extra or {}) do params[k] = v end
  local r = loom.renderer{graph = cfg.graph, scene = scene, width = width, height = height,
                          seed = seed, params = params}
  if shutter then r:shutter(shutter[1], shutter[2]) end
  if end_pose then r:camera(end_pose) end
  return r
end

-- Keyframes that swing the camera `move_degrees` about its target (up axis) and end on the
-- scene camera at time move_frames - 1 (move = dolly: starting move_dolly further back and
-- with move_zoom times the field of view; move_end = ahead: cam is the end pose, move_dolly of
-- the way to the target, and the start is back at the scene camera).
local function swing_path(cam, path)
  local back, zoom = 1, 1
  if move == "dolly" then
    back = move_end == "ahead" and 1 / (1 - move_dolly) or 1 + move_dolly
    zoom = move_zoom
  end
  util.swing_path(cam, path, {degrees = move_degrees, frames = move_frames, back = back,
                              zoom = zoom})
end

local rows, summary, stage_rows = {}, {}, {}
for _, scene_arg in ipairs(scenes) do
  local scene = resolve(scene_arg)
  if not scene then
    print("skipping " .. scene_arg .. " (not found)")
    goto next_scene
  end
  do
    local name = stem_of(scene)
    end_pose = nil
    if move_end == "ahead" then
      local probe = loom.renderer{graph = "graphs/pt.json", scene = scene, width = 8, height = 8}
      local c = probe:camera()
      probe:close()
      local o, t = c.origin, c.target
      end_pose = {origin = {o[1] + move_dolly * (t[1] - o[1]), o[2] + move_dolly * (t[2] - o[2]),
                            o[3] + move_dolly * (t[3] - o[3])},
                  target = t, up = c.up, fov = c.fov}
    end
    local ref = util.reference{scene = scene, width = width, height = height, camera = end_pose,
                               frames = ref_frames, spp = ref_spp, shutter = shutter,
                               params = {["pt.maxBounces"] = ref_bounces},
                               path = string.format("out/reference/%s_%dx%d_%dx%dspp_b%d%s%s.exr",
                                                    name, width, height, ref_frames, ref_spp,
                                                    ref_bounces, shutter and string.format(
                                                        "_shutter%g-%g", shutter[1], shutter[2])
                                                        or "",
                                                    end_pose and string.format("_ahead%g",
                                                        move_dolly) or "")}
    local ms_per_frame, pass_ms = {}, {}
    local static_series = {}
    local want = {}
    for _, c in ipairs(cameras) do want[c] = true end

    -- Static camera: convergence at equal GPU time (always run: it measures ms/frame).
    for c, cfg in ipairs(configs) do
      local r = renderer(cfg, scene)
      local port = cfg.output or "accum.output"
      r:frame()  -- untimed warm-up (pipeline creation), then start over
      r:reset()
      local spent, frames, xs, ys = 0, 0, {}, {}
      local nsteps = want.static and steps or 1
      for k = 1, nsteps do
        local target = want.static and budget * 2 ^ (k - steps) or budget / 2 ^ (steps - 1)
        local n, t = r:run_for_ms(math.max(0, target - spent))
        frames, spent = frames + n, spent + t
        local img = r:image(port)
        local row = {index = #rows + 1, scene = name, camera = "static", config = cfg.name,
                     budget_ms = target, gpu_ms = spent, frames = frames,
                     relmse = loom.metrics.relmse(img, ref), mse = loom.metrics.mse(img, ref),
                     mape = loom.metrics.mape(img, ref)}
        if want.static then
          row.relmse_trim = trimmed_relmse(img, ref, trim)
          rows[#rows + 1] = row
        end
        xs[k], ys[k] = spent, row.relmse
      end
      ms_per_frame[c] = spent / frames
      -- Per-stage GPU times of the last frame (r:timings()).
      for _, p in ipairs(r:timings().passes) do
        pass_ms[cfg.name .. "/" .. p.pass] = p.ms
        stage_rows[#stage_rows + 1] = {scene = name, config = cfg.name, pass = p.pass, ms = p.ms}
      end
      if want.static then
        static_series[c] = {name = cfg.name, x = xs, y = ys}
        summary[#summary + 1] = {scene = name, camera = "static", config = cfg.name,
                                 frames = frames, gpu_ms = spent, ms_per_frame = spent / frames,
                                 relmse = ys[#ys], mse = rows[#rows].mse, mape = rows[#rows].mape,
                                 relmse_trim = rows[#rows].relmse_trim}
        r:capture("tm.output", string.format("%s/%s_%s_static.png", out, name, slug(cfg.name)))
      end
      r:close()
      loom.progress(c, #configs, name .. " static")
    end
    if want.static then
      loom.plot{path = string.format("%s/%s_static", out, name),
                title = string.format("%s %dx%d: relMSE vs GPU time (static camera)", name,
                                      width, height),
                x_label = "GPU time (ms)", y_label = "relMSE", log_x = true,
                log_y = util.all_positive(static_series), series = static_series}
    end

    -- Moving camera: same frames for everyone. Configurations without spp_param run first; the
    -- others raise spp_param until their frame time matches the slowest of those.
    for _, kind in ipairs({"moving", "still"}) do
    if want[kind] then
      local path = string.format("%s/%s_path.json", out, name)
      local order = {}
      for c, cfg in ipairs(configs) do if not cfg.spp_param then order[#order + 1] = c end end
      for c, cfg in ipairs(configs) do if cfg.spp_param then order[#order + 1] = c end end
      local target_ms, path_written = 0, false
      for _, c in ipairs(order) do
        local cfg = configs[c]
        local r = renderer(cfg, scene)
        if kind == "moving" then
          if not path_written then swing_path(r:camera(), path) end
          path_written = true
          r:camera_path(path)
        else
          -- Still: hold the camera at its time-0 pose (the reference's), also in scenes whose
          -- camera has a path of its own (r:camera{...} replaces the path).
          r:camera(r:camera())
        end
        r:set_time(0)
        local spp = 1
        if cfg.spp_param then
          -- Frame time = fixed + spp x cost of the spp pass: a first guess from the static run,
          -- then two corrections from frames measured at the first pose.
          local pass = cfg.spp_param:match("^([^.]+)")
          local cost = pass_ms[cfg.name .. "/" .. pass] or ms_per_frame[c]
          local fixed = math.max(0, ms_per_frame[c] - cost)
          spp = math.max(1, math.floor((target_ms - fixed) / cost + 0.5))
          -- The corrections split each measured frame into the spp pass and the rest: where the
          -- rest dominates (an L1 solve), frame-to-frame noise in it would swamp the spp cost.
          local max_spp = (r:params()[cfg.spp_param] or {}).max or math.huge
          spp = math.min(spp, max_spp)
          for _ = 1, 2 do
            r:set(cfg.spp_param, spp)
            r:frame()
            local ms, pass_cost = 0, 0
            for _ = 1, 3 do
              r:frame()
              local t = r:timings()
              ms = ms + t.frame_ms / 3
              for _, p in ipairs(t.passes) do
                if p.pass == pass then pass_cost = pass_cost + p.ms / 3 end
              end
            end
            fixed = math.max(0, ms - pass_cost)
            local per_spp = math.max(1e-3, pass_cost / spp)
            spp = math.min(max_spp, math.max(1, math.floor((target_ms - fixed) / per_spp + 0.5)))
          end
          r:set(cfg.spp_param, spp)
        end
        local sum_relmse, sum_trim, sum_mape, sum_ms, total_frames = 0, 0, 0, 0, 0
        local sum_rays, sum_relmse2, sum_flip, sum_mse, sum_mse2 = 0, 0, 0, 0, 0
        for rep = 1, repeats do
          r:set_seed(seed + 100 * rep)
          r:set_time(0)
          r:frame()  -- warm-up at the first pose, then history and accumulation start over
          r:reset()
          for f = 0, move_frames - 1 do
            r:set_time(f)
            r:frame()
            sum_ms = sum_ms + r:timings().frame_ms
            total_frames = total_frames + 1
            for key, value in pairs(r:stats()) do  -- every pass's ray counter ("pt.rays", ...)
              if key:match("%.rays$") then sum_rays = sum_rays + value end
            end
          end
          local img = r:image(cfg.output or "accum.output")
          local relmse = loom.metrics.relmse(img, ref)
          sum_relmse = sum_relmse + relmse
          sum_relmse2 = sum_relmse2 + relmse * relmse
          local mse = loom.metrics.mse(img, ref)
          sum_mse, sum_mse2 = sum_mse + mse, sum_mse2 + mse * mse
          sum_trim = sum_trim + trimmed_relmse(img, ref, trim)
          sum_mape = sum_mape + loom.metrics.mape(img, ref)
          sum_flip = sum_flip + loom.metrics.flip(img, ref)
          if rep == 1 then
            r:capture("tm.output", string.format("%s/%s_%s_%s.png", out, name,
                                                 slug(cfg.name), kind))
          end
        end
        r:close()
        if not cfg.spp_param then target_ms = math.max(target_ms, sum_ms / total_frames) end
        local row = {index = #rows + 1, scene = name, camera = kind, config = cfg.name,
                     frames = total_frames, gpu_ms = sum_ms, spp = spp,
                     relmse = sum_relmse / repeats, relmse_trim = sum_trim / repeats,
                     mse = sum_mse / repeats, mape = sum_mape / repeats, flip = sum_flip / repeats}
        rows[#rows + 1] = row
        summary[#summary + 1] = {scene = name, camera = kind, config = cfg.name,
                                 frames = total_frames, gpu_ms = sum_ms, spp = spp,
                                 ms_per_frame = sum_ms / total_frames,
                                 rays_per_frame = sum_rays / total_frames, relmse = row.relmse,
                                 relmse_se = repeats > 1 and math.sqrt(math.max(0, sum_relmse2
                                     / repeats - row.relmse ^ 2) / (repeats - 1)) or nil,
                                 relmse_trim = row.relmse_trim, mse = row.mse,
                                 mse_se = repeats > 1 and math.sqrt(math.max(0, sum_mse2 / repeats
                                     - row.mse ^ 2) / (repeats - 1)) or nil,
                                 mape = row.mape, flip = row.flip}
        loom.progress(#summary, #summary, name .. " " .. kind)
      end
    end
    end
  end
  ::next_scene::
end

-- relMSE ratio: the first configuration's relMSE over each one's (> 1: better than it).
for _, row in ipairs(summary) do
  for _, base in ipairs(summary) do
    if base.scene == row.scene and base.camera == row.camera and base.config == configs[1].name then
      row.ratio = base.relmse / row.relmse
      row.ratio_trim = base.relmse_trim / row.relmse_trim
      -- Equal rays (a proxy for GPU time where traversal dominates): the base's relMSE scaled
      -- to as many samples per pixel as this configuration's rays per frame buy, assuming
      -- relMSE ~ 1 / spp for independent samples.
      -- Equal time without the rounding of spp_param: the base's relMSE scaled by its frame time
      -- over this one's (relMSE ~ 1 / time for independent samples).
      if base.spp and row.ms_per_frame and base.ms_per_frame then
        row.ratio_time = base.relmse * base.ms_per_frame / row.ms_per_frame / row.relmse
        -- MSE, the metric of the gradient-domain papers (relMSE weighs dark pixels up, where a
        -- gradient-domain solve spreads non-integrable gradient noise: bench/README.md).
        if base.mse and row.mse and row.mse > 0 then
          row.ratio_mse_time = base.mse * base.ms_per_frame / row.ms_per_frame / row.mse
        end
      end
      if base.spp and row.rays_per_frame and base.rays_per_frame and base.rays_per_frame > 0 then
        local spp_equal_rays = row.rays_per_frame / (base.rays_per_frame / base.spp)
        row.spp_equal_rays = spp_equal_rays
        row.ratio_rays = base.relmse * base.spp / spp_equal_rays / row.relmse
      end
    end
  end
end

print(string.format("\nequal time at %dx%d: static %.0f GPU ms per configuration; still/moving "
                    .. "%d frames x %d repeats", width, height, budget, move_frames, repeats))
util.print_table({{key = "scene"}, {key = "camera"}, {key = "config"},
                  {key = "frames", fmt = "%d"}, {key = "spp", fmt = "%d"},
                  {key = "gpu_ms", title = "GPU ms", fmt = "%.0f"},
                  {key = "ms_per_frame", title = "ms/frame", fmt = "%.1f"},
                  {key = "relmse", title = "relMSE", fmt = "%.5f"},
                  {key = "relmse_se", title = "(std. err.)", fmt = "%.5f"},
                  {key = "relmse_trim", title = "relMSE trim", fmt = "%.5f"},
                  {key = "mse", title = "MSE", fmt = "%.5g"},
                  {key = "mse_se", title = "(std. err.)", fmt = "%.2g"},
                  {key = "mape", title = "MAPE", fmt = "%.4f"},
                  {key = "flip", title = "FLIP", fmt = "%.4f"},
                  {key = "ratio", title = configs[1].name .. "/this relMSE", fmt = "%.2f"},
                  {key = "ratio_trim", title = "(trim)", fmt = "%.2f"},
                  {key = "ratio_time", title = "at equal time (scaled)", fmt = "%.2f"},
                  {key = "ratio_mse_time", title = "MSE at equal time", fmt = "%.2f"},
                  {key = "rays_per_frame", title = "rays/frame", fmt = "%.0f"},
                  {key = "ratio_rays", title = "at equal rays", fmt = "%.2f"}},
                 summary)
print("\nGPU ms per pass (last static frame)")
util.print_table({{key = "scene"}, {key = "config"}, {key = "pass"},
                  {key = "ms", title = "GPU ms", fmt = "%.2f"}}, stage_rows)

loom.write_csv(out .. "/restir_equal_time.csv", rows,
               {columns = {"index", "scene", "camera", "config", "budget_ms", "gpu_ms",
                           "frames", "spp", "relmse", "relmse_trim", "mse", "mape", "flip"}})
loom.write_csv(out .. "/summary.csv", summary,
               {columns = {"scene", "camera", "config", "frames", "spp", "gpu_ms",
                           "ms_per_frame", "relmse", "relmse_se", "relmse_trim", "mse", "mse_se",
                           "mape", "flip", "ratio", "ratio_trim", "ratio_time", "ratio_mse_time",
                           "rays_per_frame", "spp_equal_rays",
                           "ratio_rays"}})
print(string.format("\nwrote %s/restir_equal_time.csv, %s/summary.csv and plots", out, out))
