-- sms_equal_time.lua: caustic estimators at equal GPU time against a path-traced reference,
-- inside the caustic region and per image region. Default configurations
-- (bench/data/sms_configs.json): PT, unbiased SMS, biased SMS with M = 1, 4, 16, MNEE.
--
--   loom run scripts/sms_equal_time.lua [width=64 height=64 budget_ms=8000 steps=4 ...]
--
-- The caustic region: pixels where an unbiased SMS caustic estimate (graphs/sms.json,
-- accumCaustic.output, mask_frames frames, estimates at mask_receivers receivers per path,
-- default 1) is at least mask_fraction of the reference's luminance, i.e. where SMS-covered
-- light is a large part of the pixel.
-- Each configuration renders until its summed GPU frame times reach budget_ms * 2^(k - steps),
-- k = 1..steps (r:run_for_ms); at each step: relMSE over the image and over the caustic region
-- (loom.metrics' relMSE, eps 0.01) and the RMSE over the caustic region (RGB). The last step
-- gives:
--   - ratio: PT's caustic-region relMSE over this configuration's at equal time (relMSE times
--     GPU ms, since relMSE ~ 1 / time for these consistent estimators and the frame counts
--     miss the budget by up to a frame);
--   - energy: luminance summed over the caustic region relative to the reference (the energy
--     biased SMS and MNEE lose), and the same per block of a regions x regions grid (worst
--     block shown, blocks under 5% of the average block's reference skipped; all in the CSV).
-- per_frame=F (default 0, off) also measures one frame's own image: the relMSE in the caustic
-- region of frame F of a fresh sequence (frame F's image = F acc_F - (F - 1) acc_{F-1} of the
-- graph's accumulated output), averaged over per_frame_sequences (4) sequences, with that
-- frame's GPU ms: what a real-time estimator with reuse delivers per frame, where the
-- accumulated error above counts its frames' correlation against it.
-- ref_graph=graphs/sms.json renders the reference by that graph's accum.output over ref_frames
-- frames instead of the path tracer (for scenes whose small lights the path tracer cannot find).
-- caustic_ref_frames=K (default 0, off) compares the caustic alone: each configuration's
-- `output` (give the caustic's accumulated port, e.g. accumCaustic.output) against unbiased SMS's
-- caustic at primary receivers over K frames (graphs/sms.json, sms.receiverDepth 0,
-- accumCaustic.output), in the same caustic region. It leaves out what every estimator of the
-- caustic shares, the path part (whose fireflies otherwise dominate some scenes' errors).
-- Arguments: scenes (comma list; missing files are skipped), width, height, budget_ms, steps,
-- ref_frames, ref_spp, ref_graph, mask_frames, mask_fraction, mask_receivers, regions, seed,
-- configs, out,
-- per_frame, per_frame_sequences.
-- Writes OUT/sms_equal_time.csv (every step), OUT/sms_regions.csv (energy per block),
-- OUT/<scene>_caustic_relmse.png/.svg (convergence), OUT/<scene>_mask.png; prints tables.
local util = require("util")

local width, height = loom.arg("width", 64), loom.arg("height", 64)
local budget = loom.arg("budget_ms", 8000.0)
local steps = loom.arg("steps", 4)
local ref_frames, ref_spp = loom.arg("ref_frames", 64), loom.arg("ref_spp", 64)
local mask_frames = loom.arg("mask_frames", 16)
local mask_fraction = loom.arg("mask_fraction", 0.25)
local mask_receivers = loom.arg("mask_receivers", 1)
local regions = loom.arg("regions", 4)
local seed = loom.arg("seed", 1)
local out = loom.arg("out", "out/sms_equal_time")
local scenes = loom.arg("scenes", {"scenes/glass_sphere.json", "scenes/curved_mirror.json",
                                   "scenes/wavy_slab.json"})
local configs = loom.read_json(util.resolve(loom.arg("configs", "bench/data/sms_configs.json")))
local per_frame, per_frame_sequences = loom.arg("per_frame", 0), loom.arg("per_frame_sequences", 4)
local ref_graph = loom.arg("ref_graph", "")
local caustic_ref_frames = loom.arg("caustic_ref_frames", 0)

local function lum(r, g, b) return 0.2126 * r + 0.7152 * g + 0.0722 * b end

-- Per-pixel relMSE as loom.metrics.relmse computes it (RGB mean, eps 0.01).
local function pixel_relmse(img, ref, x, y)
  local a1, a2, a3 = img:get(x, y)
  local b1, b2, b3 = ref:get(x, y)
  return ((a1 - b1) ^ 2 / (b1 ^ 2 + 0.01) + (a2 - b2) ^ 2 / (b2 ^ 2 + 0.01)
          + (a3 - b3) ^ 2 / (b3 ^ 2 + 0.01)) / 3
end

-- Errors of img against ref: relMSE and RMSE inside the mask, luminance ratio inside the mask,
-- and the luminance ratio per block.
local function measure(img, ref, mask)
  local err, sq, n, sum, sum_ref = 0, 0, 0, 0, 0
  local block, block_ref = {}, {}
  for i = 1, regions * regions do block[i], block_ref[i] = 0, 0 end
  for y = 0, height - 1 do
    for x = 0, width - 1 do
      local l, lr = lum(img:get(x, y)), lum(ref:get(x, y))
      local b = (y * regions // height) * regions + (x * regions // width) + 1
      block[b], block_ref[b] = block[b] + l, block_ref[b] + lr
      if mask[y * width + x + 1] then
        err, n = err + pixel_relmse(img, ref, x, y), n + 1
        local a1, a2, a3 = img:get(x, y)
        local b1, b2, b3 = ref:get(x, y)
        sq = sq + ((a1 - b1) ^ 2 + (a2 - b2) ^ 2 + (a3 - b3) ^ 2) / 3
        sum, sum_ref = sum + l, sum_ref + lr
      end
    end
  end
  -- Blocks darker than 5% of the average block carry no energy worth a ratio (nil).
  local ratios, total = {}, 0
  for i = 1, regions * regions do total = total + block_ref[i] end
  for i = 1, regions * regions do
    if block_ref[i] > 0.05 * total / (regions * regions) then
      ratios[i] = block[i] / block_ref[i]
    end
  end
  return {relmse = n > 0 and err / n or 0, rmse = n > 0 and math.sqrt(sq / n) or 0,
          energy = sum_ref > 0 and sum / sum_ref or 1,
          blocks = ratios, pixels = n}
end

local rows, summary, region_rows = {}, {}, {}
for _, scene_arg in ipairs(scenes) do
  local scene = util.resolve(scene_arg)
  if not scene then
    print("skipping " .. scene_arg .. " (not found)")
    goto next_scene
  end
  do
    local name = util.stem_of(scene)
    local ref
    if ref_graph ~= "" then
      -- Scenes whose lights the path tracer cannot find (the paper's): a long run of an
      -- estimator checked unbiased against the path tracer on the project scenes.
      ref = util.reference{scene = scene, width = width, height = height, frames = ref_frames,
                           spp = 0, graph = ref_graph,
                           path = string.format("out/reference/%s_%dx%d_%d_%s.exr", name, width,
                                                height, ref_frames, util.stem_of(ref_graph))}
    else
      ref = util.reference{scene = scene, width = width, height = height, frames = ref_frames,
                           spp = ref_spp, params = {["pt.maxBounces"] = 9}}
    end
    -- The caustic region, from an unbiased SMS caustic estimate.
    local m = loom.renderer{graph = "graphs/sms.json", scene = scene, width = width,
                            height = height, seed = seed + 7919,
                            params = {["sms.maxReceivers"] = mask_receivers}}
    m:frames(mask_frames)
    local caustic = m:image("accumCaustic.output")
    m:close()
    local mask, mask_img, count = {}, loom.new_image(width, height), 0
    for y = 0, height - 1 do
      for x = 0, width - 1 do
        local inside = lum(caustic:get(x, y)) >= mask_fraction * lum(ref:get(x, y)) and
                       lum(caustic:get(x, y)) > 0
        mask[y * width + x + 1] = inside
        if inside then
          count = count + 1
          mask_img:set(x, y, 1, 1, 1)
        else
          mask_img:set(x, y, 0, 0, 0)
        end
      end
    end
    mask_img:write(string.format("%s/%s_mask.png", out, name))
    print(string.format("%s: caustic region %d of %d pixels", name, count, width * height))
    if caustic_ref_frames > 0 then
      -- The caustic alone: unbiased SMS's caustic at primary receivers.
      ref = util.reference{scene = scene, width = width, height = height,
                           frames = caustic_ref_frames, spp = 0, graph = "graphs/sms.json",
                           params = {["sms.receiverDepth"] = 0}, output = "accumCaustic.output",
                           path = string.format("out/reference/%s_%dx%d_%d_sms_caustic.exr", name,
                                                width, height, caustic_ref_frames)}
    end

    local series, pt_final = {}, nil
    for c, cfg in ipairs(configs) do
      local r = loom.renderer{graph = cfg.graph, scene = scene, width = width, height = height,
                              seed = seed, params = cfg.params or {}}
      r:frame()  -- untimed warm-up (pipeline creation), then start over
      r:reset()
      local spent, frames, xs, ys, last = 0, 0, {}, {}, nil
      for k = 1, steps do
        local target = budget * 2 ^ (k - steps)
        local n, t = r:run_for_ms(math.max(0, target - spent))
        frames, spent = frames + n, spent + t
        local img = r:image(cfg.output or "accum.output")
        last = measure(img, ref, mask)
        rows[#rows + 1] = {index = #rows + 1, scene = name, config = cfg.name, budget_ms = target,
                           gpu_ms = spent, frames = frames,
                           relmse = loom.metrics.relmse(img, ref), relmse_caustic = last.relmse,
                           rmse_caustic = last.rmse, energy_caustic = last.energy}
        xs[k], ys[k] = spent, last.relmse
      end
      series[c] = {name = cfg.name, x = xs, y = ys}
      local worst = 1
      for i = 1, regions * regions do
        local v = last.blocks[i]
        region_rows[#region_rows + 1] = {scene = name, config = cfg.name, block = i - 1,
                                         energy = v or ""}
        if v and math.abs(v - 1) > math.abs(worst - 1) then worst = v end
      end
      local row = {scene = name, config = cfg.name, frames = frames, gpu_ms = spent,
                   ms_per_frame = spent / frames, relmse = rows[#rows].relmse,
                   relmse_caustic = last.relmse, rmse_caustic = last.rmse,
                   energy_caustic = last.energy, worst_block = worst}
      if per_frame > 0 then
        -- Frame per_frame's own image in fresh sequences (accumulation differences).
        local err, ms = 0, 0
        for k = 1, per_frame_sequences do
          local q = loom.renderer{graph = cfg.graph, scene = scene, width = width,
                                  height = height, seed = seed + 104729 * k,
                                  params = cfg.params or {}}
          local prev
          for f = 1, per_frame do
            q:frame()
            if f == per_frame - 1 then prev = q:image(cfg.output or "accum.output") end
          end
          ms = ms + q:timings().frame_ms / per_frame_sequences
          local acc = q:image(cfg.output or "accum.output")
          local img = loom.new_image(width, height)
          for y = 0, height - 1 do
            for x = 0, width - 1 do
              local a1, a2, a3 = acc:get(x, y)
              local b1, b2, b3 = 0, 0, 0
              if prev then b1, b2, b3 = prev:get(x, y) end
              img:set(x, y, per_frame * a1 - (per_frame - 1) * b1,
                      per_frame * a2 - (per_frame - 1) * b2, per_frame * a3 - (per_frame - 1) * b3)
            end
          end
          err = err + measure(img, ref, mask).relmse / per_frame_sequences
          q:close()
        end
        row.frame_relmse, row.frame_ms = err, ms
      end
      if c == 1 then pt_final = row end
      -- PT's error at this configuration's time: relMSE ~ 1 / time.
      row.ratio = (pt_final.relmse_caustic * pt_final.gpu_ms) / (last.relmse * spent)
      summary[#summary + 1] = row
      r:close()
      loom.progress(c, #configs, name)
    end
    loom.plot{path = string.format("%s/%s_caustic_relmse", out, name),
              title = name .. ": relMSE in the caustic region vs GPU time", x_label = "GPU ms",
              y_label = "relMSE", log_x = true, log_y = util.all_positive(series),
              series = series}
  end
  ::next_scene::
end

loom.write_csv(out .. "/sms_equal_time.csv", rows,
               {columns = {"scene", "config", "budget_ms", "gpu_ms", "frames"}})
loom.write_csv(out .. "/sms_regions.csv", region_rows, {columns = {"scene", "config", "block"}})
print(string.format("\nequal GPU time (%.0f ms), %dx%d; caustic region: SMS caustic >= %.2f of "
                    .. "the reference; ratio = %s relMSE / relMSE at equal time%s", budget, width,
                    height, mask_fraction, configs[1].name,
                    caustic_ref_frames > 0 and "; the caustic alone against SMS's" or ""))
util.print_table({{key = "scene"}, {key = "config"}, {key = "frames"},
                  {key = "ms_per_frame", title = "ms/frame", fmt = "%.1f"},
                  {key = "relmse", title = "relMSE", fmt = "%.4g"},
                  {key = "relmse_caustic", title = "relMSE caustic", fmt = "%.4g"},
                  {key = "rmse_caustic", title = "RMSE caustic", fmt = "%.4g"},
                  {key = "ratio", title = "ratio vs " .. configs[1].name, fmt = "%.2f"},
                  {key = "energy_caustic", title = "energy caustic", fmt = "%.3f"},
                  {key = "worst_block", title = "worst block", fmt = "%.3f"}}, summary)
if per_frame > 0 then
  print(string.format("\none frame's image (frame %d of a fresh sequence, mean over %d sequences): "
                      .. "relMSE in the caustic region, its GPU ms, and their product", per_frame,
                      per_frame_sequences))
  for _, row in ipairs(summary) do row.frame_cost = row.frame_relmse * row.frame_ms end
  util.print_table({{key = "scene"}, {key = "config"},
                    {key = "frame_relmse", title = "frame relMSE caustic", fmt = "%.4g"},
                    {key = "frame_ms", title = "frame ms", fmt = "%.1f"},
                    {key = "frame_cost", title = "relMSE x ms", fmt = "%.4g"}}, summary)
end
