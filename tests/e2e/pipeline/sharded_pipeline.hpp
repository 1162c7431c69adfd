#pragma once
// A shared step, a 4-cell sweep and a gather, each appending its name to runs.txt: the
// pipeline of the shard and Slurm tests, which check that every step runs exactly once.
namespace tomodem::pipeline::test {
inline constexpr const char* kShardedPipeline = R"(steps:
  prep:
    cmd: echo prep > ${outs.0} && echo prep >> runs.txt
    outs: [prep.txt]
  cell:
    matrix: {d: [1, 2, 3, 4]}
    cmd: cat ${steps.prep.outs.0} > ${outs.0} && echo ${cell} >> runs.txt
    outs: ['c${cell}.txt']
  gather:
    cmd: cat ${steps.cell.outs} > ${outs.0} && echo gather >> runs.txt
    outs: [table.txt]
)";
}  // namespace tomodem::pipeline::test
