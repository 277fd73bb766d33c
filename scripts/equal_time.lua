-- equal_time.lua: several path tracer settings at equal GPU time against a reference.
--
--   loom run scripts/equal_time.lua [width=64 height=64 budget_ms=2000 steps=6 ...]
--
-- Each configuration renders graphs/pt.json on the scene until the summed GPU frame times
-- reach budget_ms * 2^(k - steps) for k = 1..steps (r:run_for_ms); at every step the
-- accumulated image is compared with the reference (relMSE, MAPE). Writes OUT/equal_time.csv,
-- OUT/equal_time.png/.svg (relMSE vs GPU time, log-log), OUT/mape.png/.svg, and each
-- configuration's final image and relMSE false-colour map; prints the table at the full budget.
--
-- Arguments: scene, width, height, budget_ms (GPU ms per configuration), steps, seed,
-- reference (EXR; rendered and saved there when missing), ref_frames, ref_spp, out.
local util = require("util")

local scene = loom.arg("scene", "scenes/cornell_box.json")
local width, height = loom.arg("width", 64), loom.arg("height", 64)
local budget = loom.arg("budget_ms", 2000.0)
local steps = loom.arg("steps", 6)
local out = loom.arg("out", "out/equal_time")

local configs = {
  {name = "mis 1spp", params = {["pt.strategy"] = "mis", ["pt.samplesPerPixel"] = 1}},
  {name = "mis 4spp", params = {["pt.strategy"] = "mis", ["pt.samplesPerPixel"] = 4}},
  {name = "bsdf 1spp", params = {["pt.strategy"] = "bsdf", ["pt.samplesPerPixel"] = 1}},
}

local ref_frames, ref_spp = loom.arg("ref_frames", 16), loom.arg("ref_spp", 64)
local ref = util.reference{path = loom.arg("reference"), scene = scene, width = width,
                          height = height, frames = ref_frames, spp = ref_spp}

local rows, final, series_relmse, series_mape = {}, {}, {}, {}
for c, cfg in ipairs(configs) do
  local r = loom.renderer{graph = "graphs/pt.json", scene = scene, width = width,
                          height = height, seed = loom.arg("seed", 1), params = cfg.params}
  -- One untimed warm-up frame (first-use costs), then accumulation starts over.
  r:frame()
  r:reset()
  local spent, frames = 0, 0
  local xs, ys, ms = {}, {}, {}
  for k = 1, steps do
    local target = budget * 2 ^ (k - steps)
    local n, t = r:run_for_ms(math.max(0, target - spent))
    frames, spent = frames + n, spent + t
    local img = r:image("accum.output")
    local row = {index = #rows + 1, config = cfg.name, budget_ms = target, gpu_ms = spent,
                 frames = frames, spp = frames * cfg.params["pt.samplesPerPixel"],
                 relmse = loom.metrics.relmse(img, ref), mape = loom.metrics.mape(img, ref)}
    rows[#rows + 1] = row
    xs[k], ys[k], ms[k] = spent, row.relmse, row.mape
    loom.progress((c - 1) * steps + k, #configs * steps, "equal time")
  end
  final[c] = {}
  for key, v in pairs(rows[#rows]) do final[c][key] = v end
  series_relmse[c] = {name = cfg.name, x = xs, y = ys}
  series_mape[c] = {name = cfg.name, x = xs, y = ms}
  local stem = string.format("%s/%s", out, (cfg.name:gsub("[^%w]+", "_")))
  r:capture("tm.output", stem .. ".png")
  loom.metrics.error_image(r:image("accum.output"), ref, "relmse"):write(stem .. "_relmse.png")
  r:close()
end

-- Efficiency = 1 / (relMSE x time), relative to the first configuration (> 1 is better).
for _, row in ipairs(final) do
  row.ms_per_frame = row.gpu_ms / row.frames
  row.efficiency = (final[1].relmse * final[1].gpu_ms) / (row.relmse * row.gpu_ms)
end

print(string.format("\nequal time: %s at %dx%d, %.0f ms GPU per configuration", scene, width,
                    height, budget))
util.print_table({{key = "config"}, {key = "frames", fmt = "%d"}, {key = "spp", fmt = "%d"},
                  {key = "gpu_ms", title = "GPU ms", fmt = "%.1f"},
                  {key = "ms_per_frame", title = "ms/frame", fmt = "%.2f"},
                  {key = "relmse", title = "relMSE", fmt = "%.5f"},
                  {key = "mape", title = "MAPE", fmt = "%.4f"},
                  {key = "efficiency", title = "rel. efficiency", fmt = "%.2f"}}, final)

loom.write_csv(out .. "/equal_time.csv", rows,
               {columns = {"index", "config", "budget_ms", "gpu_ms", "frames", "spp", "relmse",
                           "mape"}})
local _, png = loom.plot{path = out .. "/equal_time", title = "relMSE vs GPU time (equal time)",
                         x_label = "GPU time (ms)", y_label = "relMSE", log_x = true,
                         log_y = util.all_positive(series_relmse), series = series_relmse}
loom.plot{path = out .. "/mape", title = "MAPE vs GPU time (equal time)",
          x_label = "GPU time (ms)", y_label = "MAPE", log_x = true,
          log_y = util.all_positive(series_mape), series = series_mape}
print(string.format("\nwrote %s/equal_time.csv, %s (+ .svg), %s/mape.png", out, png, out))
