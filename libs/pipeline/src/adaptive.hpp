#pragma once
// Adaptive replicas (docs/pipelines.md, "Adaptive replicas"): rounds of the scheduler, each
// adding one replica to every cell whose targets are not met yet. Private to libs/pipeline.
#include <iosfwd>
#include <string>
#include <vector>

#include "tomodem/pipeline/pipeline.hpp"
#include "tomodem/pipeline/run.hpp"

namespace tomodem::pipeline::detail {

/// One pass of the scheduler over `p`, limited to the instances flagged in `only` (nullptr:
/// all); `locked`: the caller holds the pipeline's run lock.
RunSummary run_pass(const Pipeline& p, const RunOptions& o, std::ostream* progress, const std::vector<char>* only,
                    bool locked);

/// Rounds until every replica group has stopped ("target met" or "max reached"), writing
/// p.replicas_file after each, then one pass over the whole pipeline. The caller holds the lock.
RunSummary run_adaptive(const Pipeline& p, const RunOptions& o, std::ostream& progress);

}  // namespace tomodem::pipeline::detail
