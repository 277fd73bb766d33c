-- reference.lua: a high-spp reference image with a progress bar and ETA.
--
--   loom run scripts/reference.lua scene=scenes/cornell_box.json width=128 height=128 \
--            frames=32 out=out/reference/cornell_box.exr
--
-- Accumulates graphs/pt_reference.json (64 paths per pixel per frame, Russian roulette only
-- after 8 bounces) and writes accum.output as EXR plus a tone-mapped PNG preview next to it.
-- Arguments: graph, scene, width, height, frames, spp (0 = the graph's), seed, out.
local graph = loom.arg("graph", "graphs/pt_reference.json")
local scene = loom.arg("scene", "scenes/cornell_box.json")
local width, height = loom.arg("width", 128), loom.arg("height", 128)
local frames = loom.arg("frames", 32)
local spp = loom.arg("spp", 0)
local out = loom.arg("out", "out/reference/cornell_box.exr")

local r = loom.renderer{graph = graph, scene = scene, width = width, height = height,
                        seed = loom.arg("seed", 1000)}
if spp > 0 then r:set("pt.samplesPerPixel", spp) end
spp = r:get("pt.samplesPerPixel")

local start, gpu_ms = loom.time_ms(), 0
for f = 1, frames do
  r:frame()
  gpu_ms = gpu_ms + r:timings().frame_ms
  loom.progress(f, frames, "reference")
end
r:capture("accum.output", out)
local preview = out:gsub("%.%w+$", "") .. ".png"
r:capture("tm.output", preview)
print(string.format("wrote %s and %s: %dx%d, %d frames x %d spp = %d spp, %.1f s (%.0f ms GPU)",
                    out, preview, width, height, frames, spp, frames * spp,
                    (loom.time_ms() - start) / 1000, gpu_ms))
