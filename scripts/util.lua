-- Helpers shared by the shipped scripts: `local util = require("util")` (modules next to the
-- running script are found automatically).
local util = {}

-- Splits "a,b,c" into values: numbers and JSON literals are decoded, bare words stay strings.
function util.parse_list(text)
  local values = {}
  for item in text:gmatch("[^,]+") do
    local ok, v = pcall(loom.json_decode, item)
    if ok then values[#values + 1] = v else values[#values + 1] = item end  -- keeps `false`
  end
  return values
end

-- Applies every PASS.PARAM=VALUE script argument to a renderer (VALUE is JSON or a bare word).
function util.apply_param_args(r)
  local keys = {}
  for k in pairs(loom.args) do
    if type(k) == "string" and k:find("%.") then keys[#keys + 1] = k end
  end
  table.sort(keys)
  for _, k in ipairs(keys) do
    local ok, value = pcall(loom.json_decode, loom.args[k])
    if not ok then value = loom.args[k] end  -- not `ok and value or ...`: that turns false into "false"
    r:set(k, value)
  end
end

-- The reference image: read from `opts.path` when that file exists with the right size,
-- otherwise rendered with `opts.graph` (default graphs/pt_reference.json) for `opts.frames`
-- frames of `opts.spp` paths and written to `opts.path` (EXR) so the next run reuses it.
-- Default path: out/reference/<scene>_<W>x<H>_<frames>x<spp>spp.exr (shared by the scripts).
-- `opts.params` ({["pass.param"] = value}) are set on the reference renderer (e.g. maxBounces);
-- give such references their own `opts.path`. `opts.shutter` ({open, close}, frames) sets the
-- camera's shutter (with params["pt.motionBlur"] = true: a motion-blurred reference).
-- `opts.camera` ({origin, target, up, fov}) replaces the scene camera and its path.
-- A graph without a path tracer (e.g. graphs/sms.json) takes spp = 0 (one estimate per frame).
-- `opts.output` is the accumulated port to keep (default accum.output).
function util.reference(opts)
  local path = opts.path
  if path == nil then
    local stem = opts.scene:match("([^/\\]+)%.%w+$") or "scene"
    path = string.format("out/reference/%s_%dx%d_%dx%dspp.exr", stem, opts.width, opts.height,
                         opts.frames, opts.spp)
  end
  if path and path ~= "" then
    local ok, img = pcall(loom.read_image, path)
    if ok and img:width() == opts.width and img:height() == opts.height then
      print(string.format("reference: %s (%dx%d)", path, img:width(), img:height()))
      return img
    end
  end
  local r = loom.renderer{graph = opts.graph or "graphs/pt_reference.json", scene = opts.scene,
                          width = opts.width, height = opts.height, seed = opts.seed or 1000}
  if opts.shutter then r:shutter(opts.shutter[1], opts.shutter[2]) end
  if opts.camera then r:camera(opts.camera) end  -- {origin, target, up, fov}: replaces the path
  if opts.spp and opts.spp > 0 then r:set("pt.samplesPerPixel", opts.spp) end
  for key, value in pairs(opts.params or {}) do r:set(key, value) end
  local gpu_ms = 0
  for f = 1, opts.frames do
    r:frame()
    gpu_ms = gpu_ms + r:timings().frame_ms
    loom.progress(f, opts.frames, "reference")
  end
  local img = r:image(opts.output or "accum.output")
  if path and path ~= "" then img:write(path) end
  local spp = (opts.spp and opts.spp > 0) and r:get("pt.samplesPerPixel") or 1
  print(string.format("reference: rendered %d frames x %d spp (%.0f ms GPU)%s", opts.frames, spp,
                      gpu_ms, path and path ~= "" and (" -> " .. path) or ""))
  r:close()
  return img
end

-- Costs of a renderer along its scene's motion: frame 0 warms up (shader compiles), then frames
-- at times 1..frames. Returns the means of GPU ms per frame and of the scene update's CPU ms
-- (scene.updateMs, of which scene.bvhBuildMs and scene.adjacencyMs), and the last stats.
function util.animated_costs(r, frames)
  r:set_time(0)
  r:frame()
  local c = {gpu_ms = 0, update_ms = 0, bvh_ms = 0, adjacency_ms = 0}
  for f = 1, frames do
    r:set_time(f)
    r:frame()
    local st = r:stats()
    c.gpu_ms = c.gpu_ms + r:timings().frame_ms / frames
    c.update_ms = c.update_ms + st["scene.updateMs"] / frames
    c.bvh_ms = c.bvh_ms + st["scene.bvhBuildMs"] / frames
    c.adjacency_ms = c.adjacency_ms + st["scene.adjacencyMs"] / frames
  end
  return c, r:stats()
end

-- Writes camera keyframes to `path` (JSON for r:camera_path): a swing of `opts.degrees` about
-- cam's target around its up axis over `opts.frames` frames, ending on cam at time frames - 1.
-- The start can also be `opts.back` times further from the target (a dolly) with `opts.zoom`
-- times the field of view.
function util.swing_path(cam, path, opts)
  local o, t, u = cam.origin, cam.target, cam.up
  local len = math.sqrt(u[1] ^ 2 + u[2] ^ 2 + u[3] ^ 2)
  local k = {u[1] / len, u[2] / len, u[3] / len}
  local v = {o[1] - t[1], o[2] - t[2], o[3] - t[3]}
  local keys = {}
  for i, deg in ipairs({opts.degrees, 0}) do
    -- Rodrigues' rotation of v about k.
    local a = math.rad(deg)
    local c, s = math.cos(a), math.sin(a)
    local kxv = {k[2] * v[3] - k[3] * v[2], k[3] * v[1] - k[1] * v[3], k[1] * v[2] - k[2] * v[1]}
    local kdv = k[1] * v[1] + k[2] * v[2] + k[3] * v[3]
    local back = i == 1 and (opts.back or 1) or 1
    local origin = {}
    for j = 1, 3 do origin[j] = t[j] + back * (v[j] * c + kxv[j] * s + k[j] * kdv * (1 - c)) end
    local fov = i == 1 and math.min(170, cam.fov * (opts.zoom or 1)) or cam.fov
    keys[i] = {time = (i - 1) * (opts.frames - 1), origin = origin, target = t, up = u,
               fov = fov}
  end
  loom.write_json(path, keys)
end

-- Prints rows as an aligned text table. columns = {{key=, title=, fmt=}, ...}.
function util.print_table(columns, rows)
  local cells, widths = {}, {}
  for c, col in ipairs(columns) do widths[c] = #(col.title or col.key) end
  for i, row in ipairs(rows) do
    cells[i] = {}
    for c, col in ipairs(columns) do
      local v = row[col.key]
      local s = v == nil and "" or (col.fmt and string.format(col.fmt, v) or tostring(v))
      cells[i][c] = s
      widths[c] = math.max(widths[c], #s)
    end
  end
  local function line(values)
    local parts = {}
    for c, s in ipairs(values) do
      -- Text left-aligned in the first column, numbers right-aligned elsewhere.
      parts[c] = c == 1 and s .. string.rep(" ", widths[c] - #s)
                        or string.rep(" ", widths[c] - #s) .. s
    end
    print(table.concat(parts, "  "))
  end
  local titles, rule = {}, {}
  for c, col in ipairs(columns) do
    titles[c] = col.title or col.key
    rule[c] = string.rep("-", widths[c])
  end
  line(titles)
  line(rule)
  for i = 1, #rows do line(cells[i]) end
end

local function exists(path)
  local f = io.open(path, "r")
  if f then f:close() end
  return f ~= nil
end

-- A file path as given, else relative to the Loom source tree (this module's parent folder),
-- as loom.renderer looks files up; nil when neither exists.
local util_source = debug and debug.getinfo(1, "S").source or ""
local util_dir = util_source:match("^@(.*)[/\\]") or "."
function util.resolve(path)
  if exists(path) then return path end
  local in_tree = util_dir .. "/../" .. path
  if path:sub(1, 1) ~= "/" and exists(in_tree) then return in_tree end
  return nil
end

-- Scene name for files and tables: the file stem, or its folder for Mitsuba's "scene.xml".
function util.stem_of(path)
  local stem = path:match("([^/\\]+)%.%w+$") or "scene"
  if stem == "scene" then stem = path:match("([^/\\]+)[/\\][^/\\]+$") or stem end
  return stem
end

-- True when every y value of every series is > 0 (a log axis can show them all).
function util.all_positive(series)
  for _, s in ipairs(series) do
    for _, y in ipairs(s.y) do
      if not (y > 0) then return false end
    end
  end
  return true
end

return util
