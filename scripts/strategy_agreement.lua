-- NEE / BSDF / MIS agreement of the reference path tracer (issue 12's table): renders
-- graphs/pt.json with each strategy, without Russian roulette, and prints nee/bsdf and
-- mis/bsdf luminance over the image and in the worst 16x16-pixel block (by |z|), with
-- standard errors from 16 batches of frames.
--   loom run scripts/strategy_agreement.lua [scene=scenes/cornell_box.json] [size=64]
--            [frames=1024] [bounces=1,2,64]
local scene = loom.arg("scene", "scenes/cornell_box.json")
local size = loom.arg("size", 64)
local frames = loom.arg("frames", 1024)
local bounceList = loom.arg("bounces", "1,2,64")
local block, batches = 16, 16
local nb = math.ceil(size / block)

local function lum(r, g, b) return 0.2126 * r + 0.7152 * g + 0.0722 * b end

-- Block sums (index nb*nb + 1 = the whole image) of one accumulated image.
local function sums(img)
  local s = {}
  for k = 1, nb * nb + 1 do s[k] = 0 end
  for y = 0, size - 1 do
    for x = 0, size - 1 do
      local v = lum(img:get(x, y))
      local k = math.floor(y / block) * nb + math.floor(x / block) + 1
      s[k] = s[k] + v
      s[nb * nb + 1] = s[nb * nb + 1] + v
    end
  end
  return s
end

-- Mean and standard error of each block's sum, over batches (batch means from the running
-- accumulated mean: frames (a, b] average to (b M_b - a M_a) / (b - a)).
local function render(strategy, bounces)
  local r = loom.renderer{graph = "graphs/pt.json", scene = scene, width = size, height = size,
    params = {["pt.strategy"] = strategy, ["pt.maxBounces"] = bounces, ["pt.rrDepth"] = 64,
              ["pt.motionBlur"] = false, ["gbuf.motionBlur"] = false}}
  local per = math.floor(frames / batches)
  local prev, stats = nil, {}
  for b = 1, batches do
    r:frames(per)
    local cur = sums(r:image("accum.output"))
    for k = 1, #cur do
      local m = prev and (b * cur[k] - (b - 1) * prev[k]) or cur[k]
      stats[k] = stats[k] or {s = 0, s2 = 0}
      stats[k].s = stats[k].s + m
      stats[k].s2 = stats[k].s2 + m * m
    end
    prev = cur
  end
  r:close()
  local out = {}
  for k, st in ipairs(stats) do
    local mean = st.s / batches
    out[k] = {mean = mean, se = math.sqrt(math.max(st.s2 / batches - mean * mean, 0) / (batches - 1))}
  end
  return out
end

local rows = {}
for bounces in tostring(bounceList):gmatch("%d+") do
  bounces = tonumber(bounces)
  local ref = render("bsdf", bounces)
  for _, s in ipairs({"nee", "mis"}) do
    local o = render(s, bounces)
    local all = #o
    local function z(k) return (o[k].mean - ref[k].mean) / math.sqrt(o[k].se ^ 2 + ref[k].se ^ 2 + 1e-30) end
    local worst = 1
    for k = 1, all - 1 do if math.abs(z(k)) > math.abs(z(worst)) then worst = k end end
    print(string.format("maxBounces %2d  %s/bsdf: image %.4f (z %+.2f), worst %dx%d block %.3f (z %+.2f)",
                        bounces, s, o[all].mean / ref[all].mean, z(all), block, block,
                        o[worst].mean / ref[worst].mean, z(worst)))
    rows[#rows + 1] = {maxBounces = bounces, strategy = s, image = o[all].mean / ref[all].mean,
                       image_z = z(all), worst_block = o[worst].mean / ref[worst].mean, worst_z = z(worst)}
  end
end
loom.write_csv("out/strategy_agreement.csv", rows,
               {columns = {"maxBounces", "strategy", "image", "image_z", "worst_block", "worst_z"}})
