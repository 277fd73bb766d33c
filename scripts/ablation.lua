-- ablation.lua: sweep one parameter at a fixed frame count; error vs a reference per value.
--
--   loom run scripts/ablation.lua param=pt.maxBounces values=1,2,3,4,6,9 frames=32
--   loom run scripts/ablation.lua --shard 0/2    # sharded: one value each, writing
--   loom run scripts/ablation.lua --shard 1/2    #   OUT/ablation.PART-0.csv and -1
--   loom merge out/ablation/ablation.csv out/ablation/ablation.PART-*.csv
--   loom run scripts/ablation.lua --phase merge  # the plot of the merged CSV
--   loom sweep-submit scripts/ablation.lua --tasks 4 reference=ref.exr   # all of it on Slurm
--
-- Values are distributed round robin over --shard I/N (loom.sweep); rows carry the value's
-- `index`, so merged shards equal the unsharded CSV. Writes OUT/ablation.csv and
-- OUT/ablation.png/.svg (unsharded, or in the merge phase), and prints the table.
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

local rows, xs, ys = {}, {}, {}
local numeric = true
for _, v in ipairs(values) do numeric = numeric and type(v) == "number" end
if loom.phase == "merge" then
  rows = loom.read_csv(out .. "/ablation.csv")  -- the merged sweep: only its plot step runs
else
  local ref_frames, ref_spp = loom.arg("ref_frames", 16), loom.arg("ref_spp", 64)
  local ref = util.reference{path = loom.arg("reference"), scene = scene, width = width,
                            height = height, frames = ref_frames, spp = ref_spp}
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
    loom.progress(#rows, math.ceil((#values - loom.shard.index) / loom.shard.count), "ablation")
    r:close()
  end
end
for _, row in ipairs(rows) do
  xs[#xs + 1], ys[#ys + 1] = numeric and row.value or row.index, row.relmse
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

if loom.phase ~= "merge" then
  loom.write_csv(out .. "/ablation.csv", rows,
                 {columns = {"index", "value", "frames", "relmse", "mape", "rmse"}})
end
-- A shard's plot would show its own values only: the merge phase plots the whole sweep.
if #rows > 0 and loom.shard.count == 1 then
  local series = {{name = string.format("%d frames", frames), x = xs, y = ys}}
  loom.plot{path = out .. "/ablation", title = "Ablation: " .. param,
            x_label = numeric and param or (param .. " (value index)"), y_label = "relMSE",
            log_y = util.all_positive(series), series = series}
end
if loom.shard.count > 1 then
  print(string.format("wrote %s/ablation.PART-%d.csv (shard %d/%d)", out, loom.shard.index,
                      loom.shard.index, loom.shard.count))
elseif loom.phase == "merge" then
  print(string.format("wrote %s/ablation.png (+ .svg) from the merged %s/ablation.csv", out, out))
else
  print(string.format("wrote %s/ablation.csv and %s/ablation.png (+ .svg)", out, out))
end
