-- make_ripple_normal_map.lua: writes scenes/textures/ripples_normal.exr, the tangent-space
-- normal map of scenes/normal_mapped_water.json: the normals of a tileable height field (a
-- few sinusoids with whole periods over the unit square), stored as Mitsuba's normalmap reads
-- them (rgb = (n + 1) / 2, n in the frame (dp/du, n x dp/du, n)).
--
--   loom run scripts/make_ripple_normal_map.lua [size=64 slope=1 out=scenes/textures/ripples_normal.exr]
--
-- The map is committed; rerun this after changing the waves.
local size = loom.arg("size", 64)
local slope = loom.arg("slope", 1.0)
local out = loom.arg("out", "scenes/textures/ripples_normal.exr")

-- Height field h(u, v) in units of the plane's width: (amplitude, periods along u, along v,
-- phase). Its gradient gives the slopes.
local waves = {{0.010, 3, 1, 0.3}, {0.007, -2, 4, 1.9}, {0.004, 5, -3, 4.1}}

local img = loom.new_image(size, size)
for y = 0, size - 1 do
  for x = 0, size - 1 do
    -- Texel centres: texture_fetch reads texel (x, y) at uv = ((x + 0.5) / size, (y + 0.5) / size).
    local u, v = (x + 0.5) / size, (y + 0.5) / size
    local du, dv = 0, 0
    for _, w in ipairs(waves) do
      local a, fu, fv, ph = w[1], w[2], w[3], w[4]
      local c = math.cos(2 * math.pi * (fu * u + fv * v) + ph) * 2 * math.pi * a
      du, dv = du + c * fu, dv + c * fv
    end
    local nx, ny, nz = -slope * du, -slope * dv, 1
    local len = math.sqrt(nx * nx + ny * ny + nz * nz)
    img:set(x, y, (nx / len + 1) / 2, (ny / len + 1) / 2, (nz / len + 1) / 2)
  end
end
img:write(out)
print(string.format("wrote %s (%dx%d)", out, size, size))
