-- Heavy-tail diagnostics of one estimator's per-frame image: renders `frames` independent 1 spp
-- frames of `port` (not accumulated) and reports, every `every` frames, the running mean over
-- the image (of each pixel's mean of RGB) with its standard error over frames, the fraction of
-- nonzero pixel samples, the mean of the nonzero ones, the largest pixel sample and the share
-- of the total carried by the largest 1 % of nonzero samples. A running mean that jumps when a
-- new maximum arrives, with a top-1 % share near 1, is an estimator whose frame-count standard
-- errors cannot be trusted (passes/partitioned_sms/README.md, "the glass sphere").
--
--   loom run scripts/tail_diagnostics.lua graph=graphs/psms.json port=psms.caustic \
--       scene=scenes/glass_sphere.json size=32 frames=2000 every=100 [region=0,0,16,16] \
--       psms.maxTrials=1000000 prior.presamples=1024 out=out/tail
-- (every PASS.PARAM=VALUE argument is set on the renderer). Writes OUT/tail.csv.
local util = require("util")

local graph = loom.arg("graph", "graphs/psms.json")
local port = loom.arg("port", "psms.caustic")
local scene = loom.arg("scene", "scenes/glass_sphere.json")
local size = loom.arg("size", 32)
local frames = loom.arg("frames", 1000)
local every = loom.arg("every", 100)
local seed = loom.arg("seed", 5)
local out = loom.arg("out", "out/tail")
-- region=x,y,w,h: the statistics of that pixel rectangle only (default: the whole image).
local region = loom.arg("region", {0, 0, size, size})
if #region ~= 4 or region[3] < 1 or region[4] < 1 or region[1] < 0 or region[2] < 0 or
    region[1] + region[3] > size or region[2] + region[4] > size then
    error(string.format("region: x,y,w,h inside the %dx%d image", size, size))
end
local x0, y0, w, h = region[1], region[2], region[3], region[4]

local r = loom.renderer{graph = graph, scene = scene, width = size, height = size, seed = seed}
util.apply_param_args(r)
r:mark_output(port)
local rows = {}
print(string.format("%s %s on %s, %dx%d, seed %d, region %d,%d %dx%d", graph, port, scene, size,
                    size, seed, x0, y0, w, h))
print(string.format("%8s %12s %12s %9s %12s %10s %6s", "frames", "mean", "s.e.", "nonzero",
                    "mean nonzero", "max", "top 1%"))
local sum, sum2, nonzero, maxv, values = 0, 0, 0, 0, {}
for f = 1, frames do
    r:frame()
    local img = r:image(port)
    local m = 0
    for y = y0, y0 + h - 1 do
        for x = x0, x0 + w - 1 do
            local a, b, c = img:get(x, y)
            local v = (a + b + c) / 3
            if v ~= v then error(string.format("frame %d: pixel (%d, %d) is NaN", f, x, y)) end
            if v > 0 then
                nonzero = nonzero + 1
                values[#values + 1] = v
            end
            if v > maxv then maxv = v end
            m = m + v
        end
    end
    m = m / (w * h)
    sum, sum2 = sum + m, sum2 + m * m
    if f % every == 0 or f == frames then
        local mean = sum / f
        local se = f > 1 and math.sqrt(math.max(sum2 / f - mean * mean, 0) / (f - 1)) or 0
        table.sort(values)
        local total, top = 0, 0
        local k = math.max(1, math.floor(#values / 100))
        for i = 1, #values do total = total + values[i] end
        for i = math.max(1, #values - k + 1), #values do top = top + values[i] end
        local nzf = nonzero / (f * w * h)
        local meanNz = #values > 0 and total / #values or 0
        local share = total > 0 and top / total or 0
        print(string.format("%8d %12.6g %12.6g %9.5f %12.6g %10.4g %6.3f", f, mean, se, nzf,
                            meanNz, maxv, share))
        rows[#rows + 1] = {frames = f, mean = mean, stderr = se, nonzero_fraction = nzf,
                           mean_nonzero = meanNz, max = maxv, top1_share = share}
    end
end
loom.write_csv(out .. "/tail.csv", rows, {columns = {"frames", "mean", "stderr",
    "nonzero_fraction", "mean_nonzero", "max", "top1_share"}})
print("wrote " .. out .. "/tail.csv")
