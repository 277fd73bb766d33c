-- ablation.lua: sweep one parameter at a fixed frame count; error vs a reference per value.
--
--   loom run scripts/ablation.lua param=pt.maxBounces values=1,2,3,4,6,9 frames=32
--   loom run scripts/ablation.lua --shard 0/2 out=out/ablation/part0   # sharded:
--   loom run scripts/ablation.lua --shard 1/2 out=out/ablation/part1   #   one value each
--   loom merge out/ablation.csv out/ablation/part0/ablation.csv out/ablation/part1/ablation.csv
--
-- Values are distributed round robin over --shard I/N (loom.sweep); rows carry the value's
-- `index`, so merged shards equal the unsharded CSV. Writes OUT/ablation.csv and
-- OUT/ablation.png/.svg, and prints the table.
-- Arguments: param, values (comma-separated; JSON or bare words), graph, scene, width, height,
-- frames, seed, reference, ref_frames, ref_spp, out, timings (true adds a gpu_ms column,
-- which differs from run to run).
local util = require("util")

local param = loom.arg("param", "pt.maxBounces")
local values = loom.args.values and util.parse_list(loom.args.values) or {1, 2, 3, 4, 6, 9}
local graph = loom.arg("graph", "graphs/pt.json")
local scene = loom.arg("scene", "scenes/cornell_box.json")
local width, height = loom.arg("width", 64), loom.arg("height", 64)
local frames = loom.arg("frames", 32)
local out = loom.arg("out", "out/ablation")
local timings = loom.arg("timings", false)

local ref_frames, ref_spp = loom.arg("ref_frames", 16), loom.arg("ref_spp", 64)
local ref = util.reference{path = loom.arg("reference"), scene = scene, width = width,
                          height = height, frames = ref_frames, spp = ref_spp}

local rows, xs, ys = {}, {}, {}
local numeric = true
for _, v in ipairs(values) do numeric = numeric and type(v) == "number" end
for index, value in loom.sweep{name = param, values = values} do
  local r = loom.renderer{graph = graph, scene = scene, width = width, height = height,
                          seed = loom.arg("seed", 1)}
  r:set(param, value)
  local gpu_ms = 0
  for f = 1, frames do
    r:frame()
    gpu_ms = gpu_ms + r:timings().frame_ms
  end
  local img = r:image("accum.output")
  local row = {index = index, value = value, frames = frames,
               relmse = loom.metrics.relmse(img, ref), mape = loom.metrics.mape(img, ref),
               rmse = loom.metrics.rmse(img, ref)}
  if timings then row.gpu_ms = gpu_ms end
  rows[#rows + 1] = row
  xs[#xs + 1], ys[#ys + 1] = numeric and value or index, row.relmse
  loom.progress(#rows, math.ceil((#values - loom.shard.index) / loom.shard.count), "ablation")
  r:close()
end

print(string.format("\nablation of %s (%d frames, %dx%d)%s", param, frames, width, height,
                    loom.shard.count > 1 and string.format(", shard %d/%d", loom.shard.index,
                                                           loom.shard.count) or ""))
local columns = {{key = "index", fmt = "%d"}, {key = "value", title = param},
                 {key = "relmse", title = "relMSE", fmt = "%.5f"},
                 {key = "mape", title = "MAPE", fmt = "%.4f"},
                 {key = "rmse", title = "RMSE", fmt = "%.5f"}}
if timings then columns[#columns + 1] = {key = "gpu_ms", title = "GPU ms", fmt = "%.1f"} end
util.print_table(columns, rows)

loom.write_csv(out .. "/ablation.csv", rows,
               {columns = {"index", "value", "frames", "relmse", "mape", "rmse"}})
if #rows > 0 then
  local series = {{name = string.format("%d frames", frames), x = xs, y = ys}}
  loom.plot{path = out .. "/ablation", title = "Ablation: " .. param,
            x_label = numeric and param or (param .. " (value index)"), y_label = "relMSE",
            log_y = util.all_positive(series), series = series}
end
print(string.format("wrote %s/ablation.csv and %s/ablation.png (+ .svg)", out, out))
