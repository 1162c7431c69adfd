// Loading pipeline files: sweeps, references, includes, overrides, and the bad inputs that
// must be refused (with file, line and name) before anything runs.
#include <gtest/gtest.h>

#include <algorithm>

#include "scratch.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/pipeline/pipeline.hpp"

using tomodem::InputError;
using tomodem::test::Scratch;
namespace tp = tomodem::pipeline;

namespace {
const tp::Instance& by_id(const tp::Pipeline& p, const std::string& id) {
  for (const auto& in : p.instances)
    if (in.id == id) return in;
  throw std::runtime_error("no instance " + id);
}

std::vector<std::string> ids(const tp::Pipeline& p) {
  std::vector<std::string> v;
  for (const auto& in : p.instances) v.push_back(in.id);
  return v;
}

// The message of the InputError that loading `text` gives ("" when it loads).
std::string load_error(const Scratch& s, const std::string& text, tp::LoadOptions o = {}) {
  const std::string file = s.write("p.yaml", text);
  try {
    tp::load(file, o);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const char* kSweep = R"(vars:
  densities: [0.5, 0.7]
steps:
  prep:
    cmd: cp in.txt ${outs.0}
    deps: [in.txt]
    outs: [out/prep.txt]
  pack:
    matrix: {density: "${vars.densities}"}
    cell: d${matrix.density}
    params: {density: "${matrix.density}"}
    cmd: cp ${deps.src} ${outs.packing}
    deps: {src: "${steps.prep.outs.0}"}
    outs: {packing: "out/${cell}/packing.h5"}
  young:
    matrix: {density: "${vars.densities}"}
    replicas: 3
    seed: 100
    cell: d${matrix.density}-r${replica}
    cmd: young --seed ${seed} ${steps.pack.outs.packing} > ${outs.res}
    outs: {res: "out/${cell}/young.json"}
  gather:
    cmd: cat ${steps.young.outs.res} > ${outs.0}
    outs: [out/table.csv]
)";
}  // namespace

TEST(PipelineLoad, MatrixExpandsIntoNamedCellsWithTemplatedPaths) {
  Scratch s;
  s.write("in.txt", "x");
  const auto p = tp::load(s.write("p.yaml", kSweep));
  // 1 prep + 2 pack + 2x3 young + 1 gather, upstream first.
  ASSERT_EQ(p.instances.size(), 10u);
  EXPECT_EQ(p.instances.front().id, "prep");
  EXPECT_EQ(p.instances.back().id, "gather");
  const auto& pack = by_id(p, "pack[d0.7]");
  EXPECT_EQ(pack.outs.at(0).second, "out/d0.7/packing.h5");
  EXPECT_EQ(pack.params.at("density"), "0.7");
  EXPECT_EQ(pack.command, "cp out/prep.txt out/d0.7/packing.h5");
}

TEST(PipelineLoad, SharedUpstreamCellIsOneInstanceReadByEveryReplica) {
  Scratch s;
  s.write("in.txt", "x");
  const auto p = tp::load(s.write("p.yaml", kSweep));
  const auto v = ids(p);
  EXPECT_EQ(std::count_if(v.begin(), v.end(), [](const std::string& x) { return x.rfind("pack[", 0) == 0; }), 2);
  const auto pack = std::find(v.begin(), v.end(), "pack[d0.5]") - v.begin();
  for (int r = 0; r < 3; ++r) {
    const auto& y = by_id(p, "young[d0.5-r" + std::to_string(r) + "]");
    ASSERT_EQ(y.upstream.size(), 1u) << y.id;
    EXPECT_EQ(static_cast<long>(y.upstream[0]), pack) << y.id;
    EXPECT_EQ(y.deps.at(0).second, "out/d0.5/packing.h5");
  }
}

TEST(PipelineLoad, ReplicasGetConsecutiveSeedsFromTheBase) {
  Scratch s;
  s.write("in.txt", "x");
  const auto p = tp::load(s.write("p.yaml", kSweep));
  EXPECT_NE(by_id(p, "young[d0.7-r0]").command.find("--seed 100 "), std::string::npos);
  EXPECT_NE(by_id(p, "young[d0.7-r2]").command.find("--seed 102 "), std::string::npos);
  EXPECT_EQ(by_id(p, "young[d0.7-r2]").matrix.at("replica"), "2");
}

// A seed (any integer field) beyond 2^63 - 1 was clamped to it by strtoll and run: refused.
TEST(PipelineBadInput, SeedBeyondTheIntegerRangeIsRefusedNotClamped) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    seed: 99999999999999999999\n    cmd: echo ${seed} > ${outs.0}\n"
                               "    outs: [a.txt]\n");
  EXPECT_NE(m.find("p.yaml:3"), std::string::npos) << m;
  EXPECT_NE(m.find("seed"), std::string::npos) << m;
  EXPECT_NE(m.find("99999999999999999999"), std::string::npos) << m;
  EXPECT_NE(m.find("not clamped"), std::string::npos) << m;
  EXPECT_EQ(load_error(s, "steps:\n  a:\n    seed: 9223372036854775807\n    cmd: echo ${seed} > ${outs.0}\n"
                          "    outs: [a.txt]\n"), "");
}

TEST(PipelineLoad, GatherReferenceListsEveryCell) {
  Scratch s;
  s.write("in.txt", "x");
  const auto p = tp::load(s.write("p.yaml", kSweep));
  const auto& g = by_id(p, "gather");
  EXPECT_EQ(g.upstream.size(), 6u);
  EXPECT_EQ(g.deps.size(), 6u);
  EXPECT_EQ(g.command.rfind("cat out/d0.5-r0/young.json out/d0.5-r1/young.json", 0), 0u) << g.command;
}

TEST(PipelineLoad, CasesAddExplicitCellsAndDefaultNamesJoinKeyValues) {
  Scratch s;
  const auto p = tp::load(s.write("p.yaml", R"(steps:
  pack:
    cases:
      - {family: pores, density: 0.6}
      - {family: aggregates, density: 0.8}
    cmd: pack ${matrix.family} ${matrix.density} > ${outs.0}
    outs: ['out/${cell}.h5']
)"));
  ASSERT_EQ(p.instances.size(), 2u);
  EXPECT_EQ(p.instances[0].id, "pack[family-pores_density-0.6]");
  EXPECT_EQ(p.instances[1].outs[0].second, "out/family-aggregates_density-0.8.h5");
}

TEST(PipelineLoad, IncludedStepsComeFirstAndTheIncludingFileOverridesVars) {
  Scratch s;
  s.write("parts/common.yaml", R"(vars: {n: 10, tag: common}
steps:
  make:
    cmd: echo ${vars.n} ${vars.tag} > ${outs.0}
    outs: [a.txt]
)");
  const auto p = tp::load(s.write("p.yaml", R"(include: [parts/common.yaml]
vars: {n: 20}
steps:
  use:
    cmd: cat ${steps.make.outs.0} > ${outs.0}
    outs: [b.txt]
)"));
  ASSERT_EQ(ids(p), (std::vector<std::string>{"make", "use"}));
  EXPECT_EQ(p.instances[0].command, "echo 20 common > a.txt");
}

TEST(PipelineLoad, SetOverridesVariablesListsAndStepParams) {
  Scratch s;
  s.write("in.txt", "x");
  tp::LoadOptions o;
  o.overrides = {"densities=[0.6]", "steps.pack.params.density=0.9"};
  const auto p = tp::load(s.write("p.yaml", kSweep), o);
  EXPECT_EQ(p.instances.size(), 1u + 1u + 3u + 1u);
  EXPECT_EQ(by_id(p, "pack[d0.6]").params.at("density"), "0.9");
}

TEST(PipelineLoad, LiteralDollarBraceIsEscapedForTheShell) {
  Scratch s;
  const auto p = tp::load(s.write("p.yaml", "steps:\n  a:\n    cmd: echo $${HOME} > ${outs.0}\n    outs: [a.txt]\n"));
  EXPECT_EQ(p.instances[0].command, "echo ${HOME} > a.txt");
}

TEST(PipelineLoad, CommandValuesAreShellDataInEveryQuotingContext) {
  Scratch s;
  tp::LoadOptions o;
  o.overrides = {"label=a b; touch P", "list=[x y, \"it's\"]"};
  const auto p = tp::load(s.write("p.yaml", R"(vars: {label: x, list: [a]}
steps:
  a:
    cmd: echo ${vars.label} '${vars.label}' "${vars.label}" ${vars.list} > ${outs.0}
    outs: [a.txt]
)"),
                          o);
  // Outside quotes: one quoted word per value; in '...': the quote closed and reopened around
  // an escaped one; in "...": the characters the shell would read escaped.
  EXPECT_EQ(p.instances[0].command,
            "echo 'a b; touch P' 'a b; touch P' \"a b; touch P\" 'x y' 'it'\\''s' > a.txt");
  o.overrides = {"label=$(x) `y` \\ \"q\""};
  const auto d = tp::load(s.write("d.yaml", "vars: {label: x}\nsteps:\n  a:\n    cmd: echo \"${vars.label}\" > ${outs.0}\n    outs: [a.txt]\n"), o);
  EXPECT_EQ(d.instances[0].command, "echo \"\\$(x) \\`y\\` \\\\ \\\"q\\\"\" > a.txt");
}

// Computed names (docs/pipelines.md): the inner reference first, then the name it makes; a list
// variable read through a computed name stays a list (a matrix sweeps it).
const char* kScales = R"(vars:
  scale: full
  scales:
    full: {n: 1000, levels: [a, b, c]}
    small: {n: 10, levels: [a]}
  n: ${vars.scales.${vars.scale}.n}
steps:
  count:
    matrix: {level: '${vars.scales.${vars.scale}.levels}'}
    cmd: seq ${vars.n} ${vars.scales.${vars.scale}.n} > ${outs.0}
    outs: ['out/${matrix.level}.txt']
)";

TEST(PipelineLoad, ComputedNamesExpandInnermostFirstAndFollowSet) {
  Scratch s;
  const auto full = tp::load(s.write("p.yaml", kScales));
  EXPECT_EQ(ids(full), (std::vector<std::string>{"count[level-a]", "count[level-b]", "count[level-c]"}));
  EXPECT_EQ(full.instances[0].command, "seq 1000 1000 > out/a.txt");
  tp::LoadOptions o;
  o.overrides = {"scale=small"};
  const auto small = tp::load(s.write("p.yaml", kScales), o);
  EXPECT_EQ(ids(small), (std::vector<std::string>{"count[level-a]"}));
  EXPECT_EQ(small.instances[0].command, "seq 10 10 > out/a.txt");
}

TEST(PipelineLoad, FileNamedLiterallyInArgsButNotInDepsIsWarned) {
  // D12: editing g2.yaml would not re-run the step: the loader says so (stderr, via warnings).
  Scratch s;
  s.write("g2.yaml", "friction: 0.3\n");
  const std::string exe = s.write("bin/tomodem-fake", "#!/bin/sh\necho 'tomodem 0.9.0'\n");
  std::filesystem::permissions(exe, std::filesystem::perms::owner_all);
  tp::LoadOptions o;
  o.tool_dir = s.path("bin");
  const auto warnings = [&](const std::string& step) {
    return tp::load(s.write("p.yaml", "steps:\n  pack:\n    tool: fake\n" + step + "    outs: [a.txt]\n"), o).warnings;
  };
  const auto w = warnings("    args: [g2.yaml, -o, '${outs.0}']\n");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("p.yaml:4"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("step 'pack' names the file g2.yaml"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("deps:"), std::string::npos) << w[0];
  EXPECT_EQ(warnings("    args: [--config=g2.yaml]\n").size(), 1u);
  // Declared (and used through ${deps...} or written plainly), or not a file: no warning.
  EXPECT_TRUE(warnings("    deps: {config: g2.yaml}\n    args: ['${deps.config}', -o, '${outs.0}']\n").empty());
  EXPECT_TRUE(warnings("    deps: [g2.yaml]\n    args: [--config=g2.yaml]\n").empty());
  EXPECT_TRUE(warnings("    args: [nothing.yaml, '-n', '5', a.txt]\n").empty());
}

// ---- bad input: each names the file, the line and the offending name ----------------------

TEST(PipelineBadInput, CycleNamesTheStepsInIt) {
  Scratch s;
  const auto m = load_error(s, R"(steps:
  a:
    cmd: cp ${steps.b.outs.0} ${outs.0}
    outs: [a.txt]
  b:
    cmd: cp ${steps.a.outs.0} ${outs.0}
    outs: [b.txt]
)");
  EXPECT_NE(m.find("p.yaml:"), std::string::npos) << m;
  EXPECT_NE(m.find("cycle"), std::string::npos) << m;
  EXPECT_TRUE(m.find("a -> b -> a") != std::string::npos || m.find("b -> a -> b") != std::string::npos) << m;
}

TEST(PipelineBadInput, UnknownStepReference) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: echo > ${outs.0}\n    outs: [a.txt]\n  b:\n"
                               "    cmd: cat ${steps.pak.outs.0}\n");
  EXPECT_NE(m.find("p.yaml:6"), std::string::npos) << m;
  EXPECT_NE(m.find("unknown step 'pak'"), std::string::npos) << m;
}

TEST(PipelineBadInput, UnknownOutputName) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: echo > ${outs.x}\n    outs: {x: a.txt}\n  b:\n"
                               "    deps: ['${steps.a.outs.y}']\n    cmd: true\n");
  EXPECT_NE(m.find("p.yaml:6"), std::string::npos) << m;
  EXPECT_NE(m.find("no output 'y'"), std::string::npos) << m;
}

TEST(PipelineBadInput, TwoStepsWritingOneOutput) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: true\n    outs: [same.txt]\n  b:\n    cmd: true\n"
                               "    outs: [./same.txt]\n");
  EXPECT_NE(m.find("p.yaml:7"), std::string::npos) << m;
  EXPECT_NE(m.find("same.txt"), std::string::npos) << m;
  EXPECT_NE(m.find("also written by 'a'"), std::string::npos) << m;
}

TEST(PipelineBadInput, MissingInputFile) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: true\n    deps:\n      - data/nothere.tif\n");
  EXPECT_NE(m.find("p.yaml:5"), std::string::npos) << m;
  EXPECT_NE(m.find("data/nothere.tif"), std::string::npos) << m;
  EXPECT_NE(m.find("missing input"), std::string::npos) << m;
}

TEST(PipelineBadInput, UnknownTool) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    tool: nosuchverb\n");
  EXPECT_NE(m.find("p.yaml:3"), std::string::npos) << m;
  EXPECT_NE(m.find("tomodem-nosuchverb"), std::string::npos) << m;
}

TEST(PipelineBadInput, UnknownStepKey) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: true\n    output: [a.txt]\n");
  EXPECT_NE(m.find("p.yaml:4"), std::string::npos) << m;
  EXPECT_NE(m.find("steps.a.output"), std::string::npos) << m;
  EXPECT_NE(m.find("unknown key"), std::string::npos) << m;
}

TEST(PipelineBadInput, UnknownReferenceSuggestsTheEscape) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: echo ${HOME}\n");
  EXPECT_NE(m.find("p.yaml:3"), std::string::npos) << m;
  EXPECT_NE(m.find("$${"), std::string::npos) << m;
}

TEST(PipelineBadInput, UnknownValueOfAComputedNameListsTheKnownOnes) {
  Scratch s;
  tp::LoadOptions o;
  o.overrides = {"scale=tiny"};
  const auto m = load_error(s, kScales, o);
  EXPECT_NE(m.find("p.yaml:"), std::string::npos) << m;
  EXPECT_NE(m.find("'vars.scales.tiny."), std::string::npos) << m;
  EXPECT_NE(m.find("vars.scale = 'tiny'"), std::string::npos) << m;
  EXPECT_NE(m.find("vars.scales has: full, small"), std::string::npos) << m;
  // An unterminated inner reference is refused, not read as a name with a brace in it.
  EXPECT_NE(load_error(s, "vars: {a: '${vars.b${vars.c}'}\nsteps:\n  s:\n    cmd: echo ${vars.a}\n").find("unterminated"),
            std::string::npos);
}

TEST(PipelineBadInput, UnknownSetKeyAndParam) {
  Scratch s;
  s.write("in.txt", "x");
  tp::LoadOptions o;
  o.overrides = {"densitys=0.5"};
  EXPECT_NE(load_error(s, kSweep, o).find("densitys"), std::string::npos);
  o.overrides = {"steps.pack.params.dens=0.5"};
  EXPECT_NE(load_error(s, kSweep, o).find("dens"), std::string::npos);
}

TEST(PipelineLoad, SetTrimsSpacesAroundTheValue) {
  // D18: " 64" would be a new param value (a re-run of every instance) for a shell-line accident.
  Scratch s;
  s.write("in.txt", "x");
  tp::LoadOptions o;
  o.overrides = {"steps.pack.params.density= 0.9 ", "densities =[0.6]\t"};
  const auto p = tp::load(s.write("p.yaml", kSweep), o);
  EXPECT_EQ(by_id(p, "pack[d0.6]").params.at("density"), "0.9");
}

TEST(PipelineBadInput, SetWithAnEmptyValueIsRefused) {
  // D18: `--set densities=$UNSET` must not make a cell named "d".
  Scratch s;
  s.write("in.txt", "x");
  tp::LoadOptions o;
  for (const std::string set : {"densities=", "densities=  ", "steps.pack.params.density="}) {
    o.overrides = {set};
    const std::string m = load_error(s, kSweep, o);
    EXPECT_NE(m.find("--set"), std::string::npos) << set << ": " << m;
    EXPECT_NE(m.find("empty value"), std::string::npos) << set << ": " << m;
    EXPECT_NE(m.find(set.substr(0, set.find('='))), std::string::npos) << set << ": " << m;
  }
}

TEST(PipelineBadInput, ExponentialVariableExpansionIsRefused) {
  // D20: 9 levels, each referring 10 times to the one below, hung the loader; now the first
  // variable past 1 MB is named.
  Scratch s;
  std::string text = "vars:\n  s0: xxxxxxxxxx\n";
  for (int k = 1; k <= 8; ++k) {
    text += "  s" + std::to_string(k) + ": '";
    for (int r = 0; r < 10; ++r) text += (r ? " ${vars.s" : "${vars.s") + std::to_string(k - 1) + "}";
    text += "'\n";
  }
  text += "steps:\n  s:\n    cmd: echo ${vars.s8} > ${outs.o}\n    outs: {o: b.txt}\n";
  const std::string m = load_error(s, text);
  EXPECT_NE(m.find("'vars.s5' expands to more than 1 MB"), std::string::npos) << m.substr(0, 300);
  EXPECT_NE(m.find("p.yaml:"), std::string::npos) << m.substr(0, 300);
}

TEST(PipelineBadInput, UnusedVariableIsRefusedWithTheClosestName) {
  // D13: a misspelt override of an included variable was silently a new variable.
  Scratch s;
  s.write("common.yaml", "vars:\n  particles: 500\n");
  const std::string m = load_error(s, "include: common.yaml\nvars: {partciles: 800}\nsteps:\n  a:\n"
                                      "    cmd: echo ${vars.particles} > ${outs.o}\n    outs: {o: a.txt}\n");
  EXPECT_NE(m.find("p.yaml:2"), std::string::npos) << m;
  EXPECT_NE(m.find("vars.partciles"), std::string::npos) << m;
  EXPECT_NE(m.find("common.yaml:2?)"), std::string::npos) << m;
  EXPECT_NE(m.find("did you mean 'vars.particles'"), std::string::npos) << m;
  // Used only through a computed name, a variable is used (kScales: scales.small.n).
  EXPECT_EQ(load_error(s, kScales), "");
  // Used only by another variable, it is used too.
  EXPECT_EQ(load_error(s, "vars: {a: '${vars.b}', b: 1}\nsteps:\n  s:\n    cmd: echo ${vars.a} > ${outs.0}\n    outs: [a.txt]\n"), "");
  // An included file may serve several pipelines: its variables this one leaves unused are fine.
  s.write("library.yaml", "vars:\n  particles: 500\n  unused_here: 1\n");
  EXPECT_EQ(load_error(s, "include: library.yaml\nsteps:\n  a:\n    cmd: echo ${vars.particles} > ${outs.o}\n"
                          "    outs: {o: a.txt}\n"), "");
  // A self-alias (a cycle in the node graph) is walked once (the fuzzer found a stack overflow).
  EXPECT_EQ(load_error(s, "steps:\n  a:\n    desc: &a [*a]\n    cmd: echo 1 > ${outs.o}\n    outs: {o: a.txt}\n"), "");
}

TEST(PipelineBadInput, MisspeltCaseKeyIsReportedAtItsLine) {
  // D21: was "this step has no matrix key 'density'" at the cmd: line.
  Scratch s;
  const std::string m = load_error(s, "steps:\n  a:\n    cases:\n      - {density: 0.5}\n      - {densty: 0.7}\n"
                                      "    cell: d${matrix.density}\n    cmd: echo ${matrix.density} > ${outs.0}\n"
                                      "    outs: ['${cell}.txt']\n");
  EXPECT_NE(m.find("p.yaml:5"), std::string::npos) << m;
  EXPECT_NE(m.find("case key 'densty'"), std::string::npos) << m;
  EXPECT_NE(m.find("(density)"), std::string::npos) << m;
}

TEST(PipelineBadInput, MergeKeysSayTheyAreNotSupported) {
  Scratch s;
  const std::string m = load_error(s, "x: &base {cmd: 'true'}\nsteps:\n  a:\n    <<: *base\n    outs: [a.txt]\n");
  EXPECT_NE(m.find("p.yaml:4"), std::string::npos) << m;
  EXPECT_NE(m.find("merge keys (<<) are not supported"), std::string::npos) << m;
}

TEST(PipelineBadInput, DuplicateCellNames) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    matrix: {x: [1, 2]}\n    cell: same\n    cmd: true\n");
  EXPECT_NE(m.find("p.yaml:4"), std::string::npos) << m;
  EXPECT_NE(m.find("same"), std::string::npos) << m;
}

TEST(PipelineBadInput, YamlSyntaxErrorHasItsLine) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: true\n    outs: [out/${cell}.h5]\n");
  EXPECT_NE(m.find("p.yaml:"), std::string::npos) << m;
  EXPECT_NE(m.find("YAML"), std::string::npos) << m;
  EXPECT_NE(m.find("quote values that use ${...}"), std::string::npos) << m;
}

namespace {
// gen sweeps 6 plain replicas per level; draw adds replicas adaptively (3 to 6) and reads gen.
const char* kAdaptive = R"(steps:
  gen:
    matrix: {level: [a, b]}
    replicas: 6
    seed: 10
    cell: ${matrix.level}-r${replica}
    cmd: echo ${seed} > ${outs.0}
    outs: ['out/${cell}.txt']
  draw:
    matrix: {level: [a, b]}
    replicas: {until: {x: 0.05}, min: 3, max: 6}
    cell: ${matrix.level}-r${replica}
    cmd: cat ${steps.gen.outs.0} > ${outs.0}
    outs: ['out/${cell}.json']
  gather:
    cmd: cat ${steps.draw.outs} ${run.replicas} > ${outs.0}
    outs: [out/all.txt]
)";

long count_step(const tp::Pipeline& p, const std::string& step, const std::string& level) {
  return std::count_if(p.instances.begin(), p.instances.end(),
                       [&](const tp::Instance& in) { return in.step == step && in.matrix.at("level") == level; });
}
}  // namespace

TEST(PipelineLoad, AdaptiveReplicasStartAtMinAndUpstreamReplicasFollow) {
  Scratch s;
  const std::string file = s.write("p.yaml", kAdaptive);
  const tp::Pipeline p = tp::load(file);
  ASSERT_EQ(p.adaptive.size(), 1u);
  EXPECT_EQ(p.adaptive[0].min, 3);
  EXPECT_EQ(p.adaptive[0].max, 6);
  ASSERT_EQ(p.groups.size(), 2u);
  EXPECT_EQ(p.groups[0].id, "draw[level=a]");
  EXPECT_EQ(p.groups[0].instances.size(), 3u);
  // Only the gen replicas a draw replica reads: 3 of 6 per level.
  EXPECT_EQ(count_step(p, "gen", "a"), 3);
  EXPECT_EQ(by_id(p, "draw[a-r2]").replica, 2);
  // The gather reads the replicas that exist, and the record by its name beside the pipeline.
  EXPECT_EQ(by_id(p, "gather").command,
            "cat out/a-r0.json out/a-r1.json out/a-r2.json out/b-r0.json out/b-r1.json out/b-r2.json p.replicas.json > "
            "out/all.txt");

  tp::LoadOptions o;
  o.use_counts = true;
  o.replica_counts = {{"draw[level=a]", 5}, {"draw[level=b]", 99}};  // clamped to max
  const tp::Pipeline q = tp::load(file, o);
  EXPECT_EQ(count_step(q, "draw", "a"), 5);
  EXPECT_EQ(count_step(q, "draw", "b"), 6);
  EXPECT_EQ(count_step(q, "gen", "a"), 5);
  EXPECT_EQ(by_id(q, "gen[a-r4]").command, "echo 14 > out/a-r4.txt");  // seed + replica, as with replicas: N
}

TEST(PipelineBadInput, AdaptiveReplicasNeedEnoughUpstreamReplicasAndTheRecordNeedsAnAdaptiveStep) {
  Scratch s;
  // draw may reach replica 5, which gen (3 replicas) does not have: found at load, not in round 3.
  std::string text = kAdaptive;
  text.replace(text.find("replicas: 6"), 11, "replicas: 3");
  const std::string e = load_error(s, text);
  EXPECT_NE(e.find("no cell of step 'gen' matches cell 'a-r3'"), std::string::npos) << e;
  text = kAdaptive;
  text.replace(text.find("{until: {x: 0.05}, min: 3, max: 6}"), 34, "2");
  const std::string r = load_error(s, text);
  EXPECT_NE(r.find("p.yaml:16"), std::string::npos) << r;
  EXPECT_NE(r.find("needs a step with `replicas: {until: ...}`"), std::string::npos) << r;
}

// Review D2: one file under two spellings (absolute and relative, or through a link) is one
// output, and an input spelt either way is read from the step that writes it.
TEST(PipelineBadInput, TwoSpellingsOfOneOutputAreOneOutput) {
  Scratch s;
  auto m = load_error(s, "steps:\n  a:\n    cmd: echo a > ${outs.0}\n    outs: [" + s.path("x.txt") +
                             "]\n  b:\n    cmd: echo b > ${outs.0}\n    outs: [x.txt]\n");
  EXPECT_NE(m.find("p.yaml:7"), std::string::npos) << m;
  EXPECT_NE(m.find("also written by 'a'"), std::string::npos) << m;
  std::filesystem::create_directory_symlink(".", s.path("self"));
  m = load_error(s, "steps:\n  a:\n    cmd: echo a > ${outs.0}\n    outs: [self/y.txt]\n"
                    "  b:\n    cmd: echo b > ${outs.0}\n    outs: [y.txt]\n");
  EXPECT_NE(m.find("p.yaml:7"), std::string::npos) << m;
  EXPECT_NE(m.find("also written by 'a' as self/y.txt"), std::string::npos) << m;
  // An absolute input that another step writes (which does not exist yet) makes it upstream.
  const auto p = tp::load(s.write("p.yaml", "steps:\n  b:\n    cmd: cat ${deps.0} > ${outs.0}\n    deps: [" +
                                                s.path("z.txt") + "]\n    outs: [b.txt]\n"
                                                "  a:\n    cmd: echo a > ${outs.0}\n    outs: [z.txt]\n"));
  ASSERT_EQ(ids(p), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(by_id(p, "b").upstream, (std::vector<std::size_t>{0}));
}

// Review D4: re-running a folder's step would move the folder aside with another step's output in it.
TEST(PipelineBadInput, OutputInsideAnotherStepsOutputFolder) {
  Scratch s;
  const auto m = load_error(s, "steps:\n  a:\n    cmd: mkdir -p ${outs.o}\n    outs: {o: out}\n"
                               "  b:\n    cmd: echo b > ${outs.o}\n    outs: {o: out/sub/b.txt}\n");
  EXPECT_NE(m.find("p.yaml:7"), std::string::npos) << m;
  EXPECT_NE(m.find("steps.b.outs.o"), std::string::npos) << m;
  EXPECT_NE(m.find("inside the output folder out of 'a' (" + s.path("p.yaml:4)")), std::string::npos) << m;
  // One step may still declare a folder and a file in it; sibling paths are fine.
  EXPECT_EQ(load_error(s, "steps:\n  a:\n    cmd: true\n    outs: [out, out/x.txt]\n"
                          "  b:\n    cmd: true\n    outs: [out2/b.txt, outx]\n"), "");
}

// Review D5: yaml-cpp resolves a repeated key first-wins or last-wins depending on how the map is
// read; every repeated key is refused, with its line.
TEST(PipelineBadInput, RepeatedKeysAreRefusedWithTheirLine) {
  Scratch s;
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      {"steps:\n  a:\n    cmd: echo a > a.txt\n    cmd: echo b > a.txt\n    outs: [a.txt]\n", "p.yaml:4", "steps.a.cmd"},
      {"vars: {n: 1, n: 2}\nsteps:\n  a:\n    cmd: echo ${vars.n} > a.txt\n    outs: [a.txt]\n", "p.yaml:1", "vars.n"},
      {"steps:\n  a:\n    params: {k: 1, k: 2}\n    cmd: echo > a.txt\n    outs: [a.txt]\n", "p.yaml:3", "steps.a.params.k"},
      {"steps:\n  a:\n    cmd: echo > ${outs.o}\n    outs: {o: first.txt, o: second.txt}\n", "p.yaml:4", "steps.a.outs.o"},
      {"steps:\n  a:\n    cmd: true\n  a:\n    cmd: false\n", "p.yaml:4", "steps.a"},
      {"steps:\n  a:\n    cmd: true\nsteps:\n  b:\n    cmd: true\n", "p.yaml:4", "steps"},
      {"steps:\n  a:\n    matrix: {d: [1, 2]}\n    cases:\n      - {d: 3, d: 4}\n    cmd: true\n", "p.yaml:5", "d"},
  };
  for (const auto& [text, where, field] : cases) {
    const auto m = load_error(s, text);
    EXPECT_NE(m.find(where), std::string::npos) << text << "\n" << m;
    EXPECT_NE(m.find(field), std::string::npos) << text << "\n" << m;
    EXPECT_NE(m.find("given twice"), std::string::npos) << text << "\n" << m;
  }
  // In an included file too, named as the including file names it.
  s.write("common.yaml", "vars:\n  n: 1\n  n: 2\n");
  const auto m = load_error(s, "include: common.yaml\nsteps:\n  a:\n    cmd: echo > a.txt\n    outs: [a.txt]\n");
  EXPECT_NE(m.find("common.yaml:3"), std::string::npos) << m;
  // Equal values under different maps are no repeat.
  EXPECT_EQ(load_error(s, "vars: {n: 1, m: {n: 2}}\nsteps:\n  a:\n    params: {n: 1}\n    cmd: echo ${vars.n} ${vars.m.n} > ${outs.n}\n"
                          "    outs: {n: a.txt}\n"), "");
}

// Review D19/D21: what would fail only at run time (or say the wrong thing) is refused at load.
TEST(PipelineBadInput, EmptyCommandLongNamesAndNonIntegerReplicaCounts) {
  Scratch s;
  auto m = load_error(s, "steps:\n  a:\n    cmd: \"\"\n    outs: [a.txt]\n");
  EXPECT_NE(m.find("p.yaml:3"), std::string::npos) << m;
  EXPECT_NE(m.find("empty command"), std::string::npos) << m;
  EXPECT_NE(load_error(s, "steps:\n  a:\n    cmd: '  '\n").find("empty command"), std::string::npos);
  m = load_error(s, "steps:\n  " + std::string(201, 's') + ":\n    cmd: true\n");
  EXPECT_NE(m.find("p.yaml:2"), std::string::npos) << m;
  EXPECT_NE(m.find("at most 200 bytes (this one has 201)"), std::string::npos) << m;
  EXPECT_EQ(load_error(s, "steps:\n  " + std::string(200, 's') + ":\n    cmd: true\n"), "");
  m = load_error(s, "steps:\n  " + std::string(200, 's') + ":\n    matrix: {k: [" + std::string(60, 'v') +
                        "]}\n    cmd: true\n");
  EXPECT_NE(m.find("use a shorter `cell:` template"), std::string::npos) << m;
  m = load_error(s, "steps:\n  a:\n    replicas: {until: {y: 0.1}, min: 3.5, max: 9}\n    cmd: true\n"
                    "    outs: [a.json]\n");
  EXPECT_NE(m.find("steps.a.replicas.min"), std::string::npos) << m;
  EXPECT_NE(m.find("expected an integer"), std::string::npos) << m;
  EXPECT_EQ(m.find("-9223372036854775808"), std::string::npos) << m;
}
