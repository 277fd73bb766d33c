-- turntable.lua: a camera path rendered to an image sequence.
--
--   loom run scripts/turntable.lua views=24 degrees=60 frames=16 out=out/turntable
--   loom run scripts/turntable.lua path=my_path.json views=48
--   ffmpeg -framerate 12 -i out/turntable/frame_%04d.png turntable.mp4
--
-- Without path=, the camera swings `degrees` around its target (about the up axis); the
-- keyframes are written to OUT/path.json and loaded with r:camera_path. With path=FILE
-- (keyframes [{"time":0,"origin":[...],"target":[...],"up":[...],"fov":45}, ...]) the views
-- sample its time range evenly. Each view accumulates `frames` frames (accumulation restarts
-- when the camera moves). Arguments: graph, scene, width, height, views, degrees, frames,
-- path, out.
local graph = loom.arg("graph", "graphs/pt.json")
local scene = loom.arg("scene", "scenes/cornell_box.json")
local width, height = loom.arg("width", 128), loom.arg("height", 128)
local views = loom.arg("views", 24)
local frames = loom.arg("frames", 16)
local out = loom.arg("out", "out/turntable")
local path = loom.arg("path", "")

local r = loom.renderer{graph = graph, scene = scene, width = width, height = height}

if path == "" then
  -- Rotate origin - target about `up` (Rodrigues) by angles spread over [-degrees/2, degrees/2].
  local cam = r:camera()
  local degrees = loom.arg("degrees", 60.0)
  local o, t, u = cam.origin, cam.target, cam.up
  local len = math.sqrt(u[1] ^ 2 + u[2] ^ 2 + u[3] ^ 2)
  local k = {u[1] / len, u[2] / len, u[3] / len}
  local v = {o[1] - t[1], o[2] - t[2], o[3] - t[3]}
  local keys = {}
  for i = 0, views - 1 do
    local a = math.rad(-degrees / 2 + degrees * (views > 1 and i / (views - 1) or 0.5))
    local c, s = math.cos(a), math.sin(a)
    local kxv = {k[2] * v[3] - k[3] * v[2], k[3] * v[1] - k[1] * v[3], k[1] * v[2] - k[2] * v[1]}
    local kdv = k[1] * v[1] + k[2] * v[2] + k[3] * v[3]
    local origin = {}
    for j = 1, 3 do
      origin[j] = t[j] + v[j] * c + kxv[j] * s + k[j] * kdv * (1 - c)
    end
    keys[#keys + 1] = {time = i, origin = origin, target = t, up = u, fov = cam.fov}
  end
  path = out .. "/path.json"
  loom.write_json(path, keys)
end

local count, last = r:camera_path(path)
local first = loom.read_json(path)
first = (first.path or first)[1].time
for i = 0, views - 1 do
  r:set_time(views > 1 and first + (last - first) * i / (views - 1) or first)
  r:frames(frames)
  r:capture("tm.output", string.format("%s/frame_%04d.png", out, i))
  loom.progress(i + 1, views, "turntable")
end
print(string.format("wrote %d views (%d keyframes, %d frames each) to %s/frame_%%04d.png", views,
                    count, frames, out))
