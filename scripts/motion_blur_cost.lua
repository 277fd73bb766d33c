-- What motion blur of moving shapes costs (run by bench/motion_blur.sh, which documents the
-- arguments): per scene and graph, GPU ms per frame and the scene update's CPU ms with the
-- shutter closed (shapes move from frame to frame only) and open (shapes also move over the
-- shutter: shutter-close vertices, a BVH without spatial splits over both ends, and kernels
-- compiled with LOOM_SHAPE_MOTION_BLUR). Frames 1..frames along the scene's own motion; frame 0
-- warms up (shader compiles).
local util = require("util")

local scenes = loom.arg("scenes", {"scenes/fine_geometry.json"})
local graphs = loom.arg("graphs", {"graphs/pt.json", "graphs/splat_motion_blur.json"})
local W, H = loom.arg("width", 256), loom.arg("height", 256)
local frames = loom.arg("frames", 4)
local shutter = loom.arg("shutter", 1)

local rows = {}
for _, scene in ipairs(scenes) do
  local path = util.resolve(scene)
  for _, graph in ipairs(graphs) do
    local row = {scene = util.stem_of(scene), graph = util.stem_of(graph)}
    for _, open in ipairs({false, true}) do
      local r = loom.renderer{graph = graph, scene = path, width = W, height = H, seed = 1}
      r:shutter(0, open and shutter or 0)
      local c = util.animated_costs(r, frames)
      r:close()
      local key = open and "blur" or "sharp"
      row[key .. "_ms"] = string.format("%.1f", c.gpu_ms)
      row[key .. "_update_ms"] = string.format("%.1f", c.update_ms)
      row[key .. "_bvh_ms"] = string.format("%.1f", c.bvh_ms)
    end
    rows[#rows + 1] = row
  end
end
print(string.format("== motion blur of moving shapes, %dx%d, %d frames, shutter %g frames", W, H,
                    frames, shutter))
util.print_table({{key = "scene"}, {key = "graph"}, {key = "sharp_ms", title = "GPU ms, sharp"},
                  {key = "blur_ms", title = "GPU ms, blur"},
                  {key = "sharp_update_ms", title = "update ms, sharp"},
                  {key = "blur_update_ms", title = "update ms, blur"},
                  {key = "sharp_bvh_ms", title = "BVH ms, sharp"},
                  {key = "blur_bvh_ms", title = "BVH ms, blur"}}, rows)
