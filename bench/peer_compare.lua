-- bench/peer_cycles.sh: one image against a reference. Prints one CSV row:
-- relmse,mean_ratio (luminance-free: the mean of RGB over the image, image / reference).
--   loom run bench/peer_compare.lua image=A.exr ref=B.exr
local img = loom.read_image(loom.arg("image", ""))
local ref = loom.read_image(loom.arg("ref", ""))
local r1, g1, b1 = img:mean()
local r0, g0, b0 = ref:mean()
print(string.format("%.6g,%.6f", loom.metrics.relmse(img, ref), (r1 + g1 + b1) / (r0 + g0 + b0)))
