-- water_caustics.lua: the animated pool (scenes/water_pool_animated.json, its water surface a
-- heightfield of the frame time t) rendered as an image sequence by MNEE with dimension
-- reduction (graphs/mnee_dr.json), as in Granizo-Hidalgo & Holzschuch 2024's videos.
--
--   loom run scripts/water_caustics.lua steps=48 dt=0.5 frames=4 out=out/water_caustics
--   ffmpeg -framerate 24 -i out/water_caustics/frame_%04d.png water.mp4
--
-- Each step sets the frame time (the scene re-tessellates the water and rebuilds its BVH and
-- triangle adjacency), accumulates `frames` frames and writes the tone-mapped image. Prints GPU
-- ms per frame, the caustic walks' statistics and the scene update's CPU time per step.
-- Arguments: graph, scene, width, height, steps, dt (frame time per step), frames, resolution
-- (the water's heightfield resolution n, 2 n^2 triangles; 0 keeps the scene's), out, and any
-- PASS.PARAM=VALUE.
local util = require("util")

local graph = loom.arg("graph", "graphs/mnee_dr.json")
local scene = util.resolve(loom.arg("scene", "scenes/water_pool_animated.json"))
local width, height = loom.arg("width", 320), loom.arg("height", 240)
local steps, dt, frames = loom.arg("steps", 24), loom.arg("dt", 0.5), loom.arg("frames", 4)
local resolution = loom.arg("resolution", 0)
local out = loom.arg("out", "out/water_caustics")

if resolution > 0 then
  -- A copy of the scene with another tessellation of every heightfield.
  local s = loom.read_json(scene)
  for _, shape in ipairs(s.shapes) do
    if shape.type == "heightfield" then shape.resolution = resolution end
  end
  local copy = string.format("%s/scene_n%d.json", out, resolution)
  loom.write_json(copy, s)
  scene = copy
end

local r = loom.renderer{graph = graph, scene = scene, width = width, height = height}
util.apply_param_args(r)
local rows = {}
for step = 0, steps - 1 do
  r:set_time(step * dt)
  r:reset()
  local gpu_ms = 0
  for _ = 1, frames do
    r:frame()
    gpu_ms = gpu_ms + r:timings().frame_ms
  end
  local file = string.format("%s/frame_%04d.png", out, step)
  r:capture("tm.output", file)
  local st = r:stats()
  rows[#rows + 1] = {step = step, time = step * dt, ms_per_frame = gpu_ms / frames,
                     triangles = st["scene.triangles"], update_ms = st["scene.updateMs"],
                     adjacency_ms = st["scene.adjacencyMs"],
                     success = st["mnee.successRate"] or 0,
                     triangles_per_walk = st["mnee.trianglesPerWalk"] or 0}
  loom.progress(step + 1, steps, "water caustics")
end
util.print_table({{key = "step"}, {key = "time", fmt = "%.2f"},
                  {key = "ms_per_frame", title = "GPU ms/frame", fmt = "%.1f"},
                  {key = "update_ms", title = "scene update ms", fmt = "%.1f"},
                  {key = "adjacency_ms", title = "adjacency ms", fmt = "%.2f"},
                  {key = "success", title = "walks solved", fmt = "%.3f"},
                  {key = "triangles_per_walk", title = "triangles/walk", fmt = "%.2f"}}, rows)
loom.write_csv(out .. "/water_caustics.csv", rows)
print(string.format("wrote %d frames to %s/frame_*.png", steps, out))
