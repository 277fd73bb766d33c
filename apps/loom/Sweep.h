#pragma once
// Sweeps beyond one process: the shard of a Slurm array task, the sweep id that tags part
// files, `loom sweep-submit` (an array job plus a dependent merge job) and the merge of a
// sweep directory (`loom merge --sweep DIR`).
#include <cstdint>
#include <string>
#include <vector>

namespace loom::sweep {

// The shard of this process when it is a Slurm array task: SLURM_ARRAY_TASK_ID minus
// SLURM_ARRAY_TASK_MIN, of SLURM_ARRAY_TASK_COUNT. In a sweep-submit job LOOM_SWEEP_TASKS
// fixes N and the base 0, so a resubmitted subset (--array=3,5) keeps its shard numbers.
// Returns false when SLURM_ARRAY_TASK_ID is not set; throws UserError on bad values.
bool slurmShard(uint32_t& index, uint32_t& count);

// Names a sweep: LOOM_SWEEP_ID, else a hash of the script's text and arguments, so every
// shard of one command line computes the same id and parts of different sweeps differ.
std::string sweepId(const std::string& script, const std::vector<std::string>& args);

// loom sweep-submit SCRIPT [ARGS] --tasks N [--dir DIR] [--sbatch OPT]... | --retry DIR
int submit(const std::vector<std::string>& args);
// loom merge --sweep DIR: checks every task's exit status (naming the failed ones, writing
// nothing), then merges each CSV the tasks wrote from its N parts.
int mergeDirectory(const std::string& dir);

extern const char* kSubmitHelp;

}  // namespace loom::sweep
