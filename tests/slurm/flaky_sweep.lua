-- Test sweep for tests/slurm: values 1..4, one row each. While the file fail_file= exists the
-- value 3 raises an error, so that one array task fails and a retry can succeed.
local fail_file = loom.arg("fail_file", "")
local out = loom.arg("out", "out/flaky")
local rows = {}
for index, value in loom.sweep{name = "v", values = {1, 2, 3, 4}} do
  if value == 3 and fail_file ~= "" and io.open(fail_file) then
    error("value 3 fails while " .. fail_file .. " exists")
  end
  rows[#rows + 1] = {index = index, value = value, square = value * value}
end
if loom.phase ~= "merge" then loom.write_csv(out .. "/flaky.csv", rows) end
