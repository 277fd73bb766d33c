-- capture.lua: render a graph for some frames and write every marked output.
--
--   loom run scripts/capture.lua graph=graphs/pt.json scene=scenes/cornell_box.json \
--            width=256 height=256 frames=64 out=out/capture pt.samplesPerPixel=4
--
-- Arguments (NAME=VALUE): graph, scene ("" for none), width, height, frames, seed, out (folder),
-- and any PASS.PARAM=VALUE to set a parameter. Tone-mapped outputs go to PNG, others to EXR.
local util = require("util")

local graph = loom.arg("graph", "graphs/pt.json")
local scene = loom.arg("scene", "scenes/cornell_box.json")
local width, height = loom.arg("width", 256), loom.arg("height", 256)
local frames = loom.arg("frames", 64)
local out = loom.arg("out", "out/capture")

local r = loom.renderer{graph = graph, scene = scene ~= "" and scene or nil, width = width,
                        height = height, seed = loom.arg("seed", 0)}
util.apply_param_args(r)

local gpu_ms = 0
for f = 1, frames do
  r:frame()
  gpu_ms = gpu_ms + r:timings().frame_ms
  loom.progress(f, frames, "capture")
end

local types = {}
for _, p in ipairs(r:passes()) do types[p.name] = p.type end
for _, port in ipairs(r:outputs()) do
  local pass = port:match("^([^.]+)")
  local ext = types[pass] == "ToneMap" and ".png" or ".exr"
  local file = string.format("%s/%s%s", out, (port:gsub("%.", "_")), ext)
  r:capture(port, file)
  print("wrote " .. file)
end
print(string.format("%d frames of %dx%d in %.1f ms GPU (%.2f ms/frame)", frames, width, height,
                    gpu_ms, gpu_ms / frames))
