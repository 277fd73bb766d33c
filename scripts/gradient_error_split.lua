-- gradient_error_split.lua: where the error of a gradient-domain reconstruction comes from.
-- The screened Poisson solve is linear, so its error splits into the part the primal's error
-- causes and the part the gradients' errors cause. For each gradient graph this renders the last
-- single frame of a camera swing (as restir_equal_time.lua's moving rows do), then solves again
-- with the exact gradients (forward differences of the reference primal) and with the exact
-- primal, and reports MSE and relMSE of each. It also reports how much of the gradient error is
-- non-integrable: the mean squared curl of the estimated gradients over twice their squared
-- error (1: independent errors per pixel edge; 0: the gradients of some image, as when every
-- gradient is a difference of the same per-pixel samples).
--
--   loom run scripts/gradient_error_split.lua [scene=scenes/glossy_spheres.json width=64
--       height=64 repeats=6 move_frames=8 move_degrees=8 ref_frames=32 ref_spp=64]
--
-- The reference primal is the PT reference (9 bounces) minus the emission seen at primary hits
-- (each graph's `direct`, accumulated over `direct_frames` still frames), the part the gradient
-- graphs leave out of the solve. The solve uses the graphs' own PoissonReconstruct settings
-- (alpha, iterations). Writes OUT/gradient_error_split.csv and per-configuration images of the
-- reconstruction with exact primal (OUT/<config>_gradient_error.png: relMSE map).
local util = require("util")

local scene_arg = loom.arg("scene", "scenes/glossy_spheres.json")
local scene = util.resolve(scene_arg)
if not scene then error("scene: file not found: " .. scene_arg) end
local W, H = loom.arg("width", 64), loom.arg("height", 64)
local repeats = loom.arg("repeats", 6)
local move_frames, move_degrees = loom.arg("move_frames", 8), loom.arg("move_degrees", 8.0)
local out = loom.arg("out", "out/gradient_error_split")
local name = util.stem_of(scene)
local configs = {
  {name = "ReSTIR G-PT", graph = "graphs/grestir_pt.json"},
  {name = "gradient after ReSTIR", graph = "graphs/gradient_after_restir.json"},
}
if loom.args.configs then configs = loom.read_json(loom.args.configs) end

local ref = util.reference{scene = scene, width = W, height = H,
                           frames = loom.arg("ref_frames", 32), spp = loom.arg("ref_spp", 64),
                           params = {["pt.maxBounces"] = 9},
                           path = string.format("out/reference/%s_%dx%d_%dx%dspp_b9.exr", name, W,
                                                H, loom.arg("ref_frames", 32),
                                                loom.arg("ref_spp", 64))}

local function map(a, b, f)  -- per-pixel RGB op into a new image
  local img = loom.new_image(W, H, 0, 0, 0, 1)
  for y = 0, H - 1 do
    for x = 0, W - 1 do
      local a1, a2, a3 = a:get(x, y)
      local b1, b2, b3 = b:get(x, y)
      img:set(x, y, f(a1, b1), f(a2, b2), f(a3, b3), 1)
    end
  end
  return img
end

-- Forward differences, 0 in the last column / row (Neumann: not equations of the solve).
local function differences(img)
  local dx, dy = loom.new_image(W, H, 0, 0, 0, 1), loom.new_image(W, H, 0, 0, 0, 1)
  for y = 0, H - 1 do
    for x = 0, W - 1 do
      local a1, a2, a3 = img:get(x, y)
      if x < W - 1 then
        local b1, b2, b3 = img:get(x + 1, y)
        dx:set(x, y, b1 - a1, b2 - a2, b3 - a3, 1)
      end
      if y < H - 1 then
        local b1, b2, b3 = img:get(x, y + 1)
        dy:set(x, y, b1 - a1, b2 - a2, b3 - a3, 1)
      end
    end
  end
  return dx, dy
end

-- Mean squared error of the solve's equations (dx: all but the last column, dy: all but the
-- last row), over RGB.
local function gradient_mse(dx, dy, rdx, rdy)
  local s = 0
  for y = 0, H - 1 do
    for x = 0, W - 1 do
      for _, g in ipairs({{dx, rdx, x < W - 1}, {dy, rdy, y < H - 1}}) do
        if g[3] then
          local a1, a2, a3 = g[1]:get(x, y)
          local b1, b2, b3 = g[2]:get(x, y)
          s = s + ((a1 - b1) ^ 2 + (a2 - b2) ^ 2 + (a3 - b3) ^ 2) / 3
        end
      end
    end
  end
  return s / ((W - 1) * H + W * (H - 1))
end

-- Mean squared curl dx(p) + dy(p + ex) - dx(p + ey) - dy(p) over the interior cells: 4 sigma^2
-- for independent errors of variance sigma^2 per edge, 0 for the differences of an image.
local function mean_squared_curl(dx, dy)
  local s = 0
  for y = 0, H - 2 do
    for x = 0, W - 2 do
      local a1, a2, a3 = dx:get(x, y)
      local b1, b2, b3 = dy:get(x + 1, y)
      local c1, c2, c3 = dx:get(x, y + 1)
      local d1, d2, d3 = dy:get(x, y)
      s = s + ((a1 + b1 - c1 - d1) ^ 2 + (a2 + b2 - c2 - d2) ^ 2 + (a3 + b3 - c3 - d3) ^ 2) / 3
    end
  end
  return s / ((W - 1) * (H - 1))
end

-- The solve on images from files (ImageLoader -> PoissonReconstruct), with a graph's settings.
local solve_graph = out .. "/solve.json"
local function solve(files, poisson)
  local r = loom.renderer{graph = solve_graph, scene = scene, width = W, height = H}
  for _, k in ipairs({"alpha", "iterations", "solver", "linearSolver"}) do
    r:set("poisson." .. k, poisson[k])
  end
  r:set("primal.path", files[1])
  r:set("dx.path", files[2])
  r:set("dy.path", files[3])
  r:frame()
  local img = r:image("poisson.output")
  r:close()
  return img
end

local ref_files = {out .. "/exact_primal.exr", out .. "/exact_dx.exr", out .. "/exact_dy.exr"}
local swing = string.format("%s/%s_path.json", out, name)
local rows = {}
for c, cfg in ipairs(configs) do
  local r = loom.renderer{graph = cfg.graph, scene = scene, width = W, height = H, seed = 1}
  local node = cfg.node or "poisson"
  local poisson = {}
  for _, k in ipairs({"alpha", "iterations", "solver", "linearSolver"}) do
    poisson[k] = r:get(node .. "." .. k)
  end
  local ports = cfg.ports or {primal = "accPrimal.output", dx = "accDx.output",
                              dy = "accDy.output", direct = "accDirect.output"}
  for _, p in pairs(ports) do r:mark_output(p) end
  r:mark_output(node .. ".output")
  if c == 1 then
    -- The exact inputs: the reference without the emission seen at primary hits.
    local still = loom.renderer{graph = cfg.graph, scene = scene, width = W, height = H, seed = 7}
    still:camera(still:camera())
    still:mark_output(ports.direct)
    still:frames(loom.arg("direct_frames", 64))
    local exact = map(ref, still:image(ports.direct), function(a, b) return a - b end)
    still:close()
    local dx, dy = differences(exact)
    exact:write(ref_files[1])
    dx:write(ref_files[2])
    dy:write(ref_files[3])
    loom.write_json(solve_graph, {
      name = "gradient_error_split_solve",
      passes = {{name = "primal", type = "ImageLoader", params = {path = ref_files[1]}},
                {name = "dx", type = "ImageLoader", params = {path = ref_files[2]}},
                {name = "dy", type = "ImageLoader", params = {path = ref_files[3]}},
                {name = "poisson", type = "PoissonReconstruct"}},
      edges = {{"primal.output", "poisson.primal"}, {"dx.output", "poisson.dx"},
               {"dy.output", "poisson.dy"}},
      outputs = {"poisson.output"}})
    util.swing_path(r:camera(), swing, {degrees = move_degrees, frames = move_frames})
    -- The split is only as good as the solve: the exact inputs must give the exact image back.
    local check = loom.metrics.relmse(solve(ref_files, poisson), exact)
    print(string.format("solve of the exact inputs: relMSE %.3g", check))
    if check > 1e-6 then error(string.format("the solve of the exact inputs is off (relMSE %g): "
                                             .. "more poisson.iterations?", check)) end
  end
  local exact = loom.read_image(ref_files[1])
  local rdx, rdy = loom.read_image(ref_files[2]), loom.read_image(ref_files[3])
  r:camera_path(swing)
  local sum = {}
  local keys = {"mse", "relmse", "mse_primal_part", "relmse_primal_part", "mse_gradient_part",
                "relmse_gradient_part", "primal_relmse", "gradient_mse", "non_integrable"}
  for _, k in ipairs(keys) do sum[k] = 0 end
  for rep = 1, repeats do
    r:set_seed(1 + 100 * rep)
    r:set_time(0)
    r:frame()
    r:reset()
    for f = 0, move_frames - 1 do
      r:set_time(f)
      r:frame()
    end
    local files, images = {}, {}
    for i, port in ipairs({ports.primal, ports.dx, ports.dy}) do
      files[i] = string.format("%s/estimate_%d.exr", out, i)
      images[i] = r:image(port)
      images[i]:write(files[i])
    end
    local full = r:image(node .. ".output")
    local with_exact_gradients = solve({files[1], ref_files[2], ref_files[3]}, poisson)
    local with_exact_primal = solve({ref_files[1], files[2], files[3]}, poisson)
    local dx, dy = images[2], images[3]
    local gmse = gradient_mse(dx, dy, rdx, rdy)
    local v = {
      mse = loom.metrics.mse(full, exact), relmse = loom.metrics.relmse(full, exact),
      mse_primal_part = loom.metrics.mse(with_exact_gradients, exact),
      relmse_primal_part = loom.metrics.relmse(with_exact_gradients, exact),
      mse_gradient_part = loom.metrics.mse(with_exact_primal, exact),
      relmse_gradient_part = loom.metrics.relmse(with_exact_primal, exact),
      primal_relmse = loom.metrics.relmse(images[1], exact), gradient_mse = gmse,
      non_integrable = mean_squared_curl(dx, dy) / (4 * gmse)}
    for _, k in ipairs(keys) do sum[k] = sum[k] + v[k] / repeats end
    if rep == 1 then
      loom.metrics.error_image(with_exact_primal, exact, "relmse", 2.0):write(
          string.format("%s/%s_%s_gradient_error.png", out, name, cfg.name:gsub("[^%w]+", "_")))
    end
    loom.progress((c - 1) * repeats + rep, #configs * repeats, "gradient error split")
  end
  r:close()
  sum.scene, sum.config = name, cfg.name
  rows[#rows + 1] = sum
end

print(string.format("\n%s %dx%d, last frame of a %d-frame swing of %g degrees, %d repeats; error "
                    .. "against the reference without primary-hit emission", name, W, H,
                    move_frames, move_degrees, repeats))
util.print_table({{key = "config"}, {key = "mse", title = "MSE", fmt = "%.4g"},
                  {key = "mse_primal_part", title = "exact gradients", fmt = "%.4g"},
                  {key = "mse_gradient_part", title = "exact primal", fmt = "%.4g"},
                  {key = "relmse", title = "relMSE", fmt = "%.4g"},
                  {key = "relmse_primal_part", title = "exact gradients", fmt = "%.4g"},
                  {key = "relmse_gradient_part", title = "exact primal", fmt = "%.4g"},
                  {key = "primal_relmse", title = "primal alone relMSE", fmt = "%.4g"},
                  {key = "gradient_mse", title = "gradient MSE", fmt = "%.4g"},
                  {key = "non_integrable", title = "non-integrable", fmt = "%.2f"}}, rows)
loom.write_csv(out .. "/gradient_error_split.csv", rows, {columns = {"scene", "config"}})
print(string.format("wrote %s/gradient_error_split.csv", out))
