-- NEE / BSDF / MIS agreement of the reference path tracer (issue 12's table): renders
-- graphs/pt.json with each strategy, without Russian roulette, and prints nee/bsdf and
-- mis/bsdf luminance over the image and in the worst 16x16-pixel block.
--   loom run scripts/strategy_agreement.lua [scene=scenes/cornell_box.json] [size=64]
--            [frames=1024] [bounces=1,2,64]
local scene = loom.arg("scene", "scenes/cornell_box.json")
local size = loom.arg("size", 64)
local frames = loom.arg("frames", 1024)
local bounceList = loom.arg("bounces", "1,2,64")
local block = 16

local function lum(r, g, b) return 0.2126 * r + 0.7152 * g + 0.0722 * b end

local function render(strategy, bounces)
  local r = loom.renderer{graph = "graphs/pt.json", scene = scene, width = size, height = size,
    params = {["pt.strategy"] = strategy, ["pt.maxBounces"] = bounces, ["pt.rrDepth"] = 64,
              ["pt.motionBlur"] = false, ["gbuf.motionBlur"] = false}}
  r:frames(frames)
  local img = r:image("accum.output")
  r:close()
  local blocks, total = {}, 0
  for y = 0, size - 1 do
    for x = 0, size - 1 do
      local v = lum(img:get(x, y))
      local k = math.floor(y / block) * math.ceil(size / block) + math.floor(x / block) + 1
      blocks[k] = (blocks[k] or 0) + v
      total = total + v
    end
  end
  return total, blocks
end

local rows = {}
for bounces in bounceList:gmatch("%d+") do
  bounces = tonumber(bounces)
  local ref, refBlocks = render("bsdf", bounces)
  for _, s in ipairs({"nee", "mis"}) do
    local t, b = render(s, bounces)
    local worst, worstRatio = 0, 1
    for k, v in pairs(b) do
      local ratio = v / refBlocks[k]
      if math.abs(ratio - 1) > worst then worst = math.abs(ratio - 1); worstRatio = ratio end
    end
    print(string.format("maxBounces %2d  %s/bsdf: image %.4f, worst %dx%d block %.3f", bounces, s,
                        t / ref, block, block, worstRatio))
    rows[#rows + 1] = {maxBounces = bounces, strategy = s, image = t / ref, worst_block = worstRatio}
  end
end
loom.write_csv("out/strategy_agreement.csv", rows, {columns = {"maxBounces", "strategy", "image", "worst_block"}})
