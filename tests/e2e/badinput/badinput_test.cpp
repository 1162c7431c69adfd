// Bad input across every tool (issue 16, "never destroy, never lie"): one table, one row per case,
// one ctest test per row. Each row runs one tool in a fresh work folder and asserts
//   - the exit code (2 for bad input),
//   - that stderr names the file or option and the value (every `names` entry, case-insensitive;
//     "a|b" accepts either),
//   - that the work folder holds exactly what it held before (no *.tmp*, no partial output),
//   - that every file in it (the inputs) is byte for byte unchanged.
// The valid inputs (a packing, a bonded packing, volumes, a level set, scenes, a pipeline) are made
// once by running the tools, cached under the build folder and copied into each row's folder.
//
// Adding a case is one line in kRows: {tool, args, exit code, {strings stderr must contain}}, plus
// an optional fifth field "what is wrong today" that skips the row until it is fixed
// (TOMODEM_BADINPUT_RUN_OPEN=1 runs those rows anyway; TOMODEM_BADINPUT_VERBOSE=1 prints each
// row's exit code and last stderr line).
// Placeholders in args (each creates W/NAME in the row's work folder W and stands for its path):
//   {NAME}            a copy of the cached valid input NAME
//   {missing:NAME}    nothing is created           {empty:NAME}  an empty file
//   {dir:NAME}        an (empty) folder            {text:NAME}   plain text, not the expected format
//   {bin:NAME}        binary bytes (NULs, 0xFF)    {half:NAME}   the cached NAME cut at 50 % (mid-line)
//   {edit:NAME:FROM=>TO}  the cached NAME with the first FROM replaced by TO
//   {link:NAME}       W/link-NAME, a symbolic link to NAME (made by another placeholder)
//   {!KIND:NAME...}   the same, but stands for nothing (a file the input refers to)
//   {W}               the work folder
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct Row {
  const char* tool;                // tomodem-<tool>
  const char* args;                // with placeholders (see above)
  int code;                        // expected exit code
  std::vector<std::string> names;  // stderr must contain each (file, option, value)
  const char* open = "";           // non-empty: a known defect, the row is skipped with this reason
};

// ---------------------------------------------------------------------------------------------
// The table. Inputs in the cache: pack.yaml -> packing.h5 -> bonded.h5 (tomodem-pack, -bond);
// grey.mha, grey.tif, truth.h5 (tomodem-phantom); labels.h5, pores.vdb (tomodem-segment);
// pore.off (a closed cube mesh); scene.yaml (tomodem-dem), sinter.yaml, pipe.yaml, row.json.
// ---------------------------------------------------------------------------------------------
const std::vector<Row> kRows = {
    // ---- tomodem-pack: config YAML -> packing
    {"pack", "{missing:pack.yaml} -o {W}/p.h5", 2, {"pack.yaml"}},
    {"pack", "{empty:pack.yaml} -o {W}/p.h5", 2, {"pack.yaml"}},
    {"pack", "{dir:pack.yaml} -o {W}/p.h5", 2, {"pack.yaml", "folder|directory"}},
    {"pack", "{text:pack.yaml} -o {W}/p.h5", 2, {"pack.yaml"}},
    {"pack", "{bin:pack.yaml} -o {W}/p.h5", 2, {"pack.yaml"}},
    {"pack", "{half:pack.yaml} -o {W}/p.h5", 2, {"pack.yaml"}},
    {"pack", "{packing.h5} -o {W}/p.h5", 2, {"packing.h5"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --particles 1000000000000", 2, {"1000000000000"}},
    {"pack", "{edit:pack.yaml:particles: 150=>particles: 1.0e12} -o {W}/p.h5", 2, {"pack.yaml", "particles"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --particles 0", 2, {"--particles", "0"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --particles -5", 2, {"--particles", "-5"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --target-solid-fraction nan", 2, {"--target-solid-fraction", "nan"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --target-solid-fraction inf", 2, {"--target-solid-fraction", "inf"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --target-pressure -1", 2, {"--target-pressure", "-1"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --friction nan", 2, {"friction", "nan"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --threads -1", 2, {"--threads", "-1"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --no-such-option", 2, {"--no-such-option"}},
    {"pack", "{pack.yaml} -o {pack.yaml}", 2, {"-o", "pack.yaml"}},
    {"pack", "{pack.yaml} -o {W}/p.h5 --json {pack.yaml}", 2, {"--json", "pack.yaml"}},
    {"pack", "{pack.yaml} -o {link:pack.yaml}", 2, {"-o", "link-pack.yaml"}},
    {"pack", "{pack.yaml} --no-tessellation -o {text:notadir}/p.h5", 2, {"-o", "notadir/p.h5"}},
    {"pack", "{edit:pack.yaml:diameter: 5.0e-5=>diameter: .nan} -o {W}/p.h5", 2, {"pack.yaml", "diameter", "nan"}},
    {"pack", "{edit:pack.yaml:density: 6000=>density: -6000} -o {W}/p.h5", 2, {"pack.yaml", "density", "-6000"}},

    // ---- tomodem-phantom: options -> volume (no input file)
    {"phantom", "-o {W}/g.mha --size 100000", 2, {"--size", "100000"}},
    {"phantom", "-o {W}/g.mha --size 0", 2, {"--size", "0"}},
    {"phantom", "-o {W}/g.mha --size -4", 2, {"--size", "-4"}},
    {"phantom", "-o {W}/g.mha --voxel nan", 2, {"--voxel", "nan"}},
    {"phantom", "-o {W}/g.mha --voxel inf", 2, {"--voxel", "inf"}},
    {"phantom", "-o {W}/g.mha --voxel 0", 2, {"--voxel", "0"}},
    {"phantom", "-o {W}/g.mha --voxel -1e-5", 2, {"--voxel", "'-1e-5'"}},
    {"phantom", "-o {W}/g.mha --snr nan", 2, {"--snr", "nan"}},
    {"phantom", "-o {W}/g.mha --blur -1", 2, {"--blur", "-1"}},
    {"phantom", "-o {W}/g.mha --kind nosuch", 2, {"--kind", "nosuch"}},
    {"phantom", "-o {W}/g.mha --no-such-option", 2, {"--no-such-option"}},
    {"phantom", "-o {text:notadir}/g.mha --size 16", 2, {"notadir/g.mha"}},
    {"phantom", "-o {W}/g.xyz --size 16", 2, {"g.xyz"}},
    {"phantom", "-o {dir:g.mha} --size 16", 2, {"g.mha"}},
    {"phantom", "-o {W}/g.mha --truth {text:notadir}/t.h5 --size 16", 2, {"notadir/t.h5"}},
    {"phantom", "-o {W}/g.mha --json {text:notadir}/s.json --size 16", 2, {"notadir/s.json"}},
    {"phantom", "-o {W}/g.mha --threads -1", 2, {"--threads", "-1"}},
    {"phantom", "-o {W}/g.mha --kind pores --macropores -1", 2, {"--macropores", "-1"}},
    {"phantom", "-o {W}/g.mha --kind pores --fine-porosity 2", 2, {"--fine-porosity", "2"}},
    {"phantom", "-o {W}/g.h5 --truth {W}/g.h5 --size 16", 2, {"g.h5"}},
    {"phantom", "-o {W}/g.h5 --truth {W}/./g.h5 --size 16", 2, {"--truth", "g.h5"}},

    // ---- tomodem-segment: volume -> labels
    {"segment", "{missing:grey.mha} -o {W}/l.h5", 2, {"grey.mha"}},
    {"segment", "{empty:grey.mha} -o {W}/l.h5", 2, {"grey.mha"}},
    {"segment", "{dir:slices} -o {W}/l.h5", 2, {"slices"}},
    {"segment", "{text:grey.mha} -o {W}/l.h5", 2, {"grey.mha"}},
    {"segment", "{bin:grey.mha} -o {W}/l.h5", 2, {"grey.mha"}},
    {"segment", "{half:grey.mha} -o {W}/l.h5", 2, {"grey.mha"}},
    {"segment", "{half:grey.tif} -o {W}/l.h5", 2, {"grey.tif"}},
    {"segment", "{text:grey.tif} -o {W}/l.h5", 2, {"grey.tif"}},
    {"segment", "{half:truth.h5} --dataset /labels -o {W}/l.h5", 2, {"truth.h5"}},
    {"segment", "{pack.yaml} -o {W}/l.h5", 2, {"pack.yaml"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --spacing nan", 2, {"--spacing", "nan"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --spacing -1um", 2, {"--spacing", "-1um"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --downsample 0", 2, {"--downsample", "0"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --roi 0,0,0,100000,100000,100000", 2, {"--roi", "100000"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --filter nosuch", 2, {"--filter", "nosuch"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --filter gaussian --sigma nan", 2, {"--sigma", "nan"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --method manual --levels nan", 2, {"--levels", "nan"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --connectivity 7", 2, {"--connectivity", "7"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --no-such-option", 2, {"--no-such-option"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --mha {grey.mha}", 2, {"--mha", "grey.mha"}},
    {"segment", "{grey.mha} -o {grey.mha}", 2, {"-o", "grey.mha"}},
    {"segment", "{grey.mha} -o {text:notadir}/l.h5", 2, {"notadir/l.h5"}},
    {"segment", "{grey.mha} -o {W}/l.h5 --mha {link:grey.mha}", 2, {"--mha", "link-grey.mha"}},
    {"segment", "{grey.mha} --format raw --raw-dims 100000,100000,100000 -o {W}/l.h5", 2, {"100000"}},

    // ---- tomodem-bond: packing -> bonded packing
    {"bond", "{missing:packing.h5} -o {W}/b.h5", 2, {"packing.h5"}},
    {"bond", "{empty:packing.h5} -o {W}/b.h5", 2, {"packing.h5"}},
    {"bond", "{dir:packing.h5} -o {W}/b.h5", 2, {"packing.h5", "folder|directory"}},
    {"bond", "{text:packing.h5} -o {W}/b.h5", 2, {"packing.h5"}},
    {"bond", "{half:packing.h5} -o {W}/b.h5", 2, {"packing.h5"}},
    {"bond", "{pack.yaml} -o {W}/b.h5", 2, {"pack.yaml"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --neck-ratio nan", 2, {"--neck-ratio", "nan"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --neck-ratio inf", 2, {"--neck-ratio", "inf"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --neck-ratio -0.1", 2, {"--neck-ratio", "-0.1"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --gap-tolerance nan", 2, {"--gap-tolerance", "nan"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --rule density --target-density 2", 2, {"--target-density", "2"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --rule nosuch", 2, {"--rule", "nosuch"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --threads -1", 2, {"--threads", "-1"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --exclude nosuch:ceramic", 2, {"--exclude", "nosuch"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --rule sinter --target-density 0.8 --sinter-config {missing:s.yaml}", 2, {"s.yaml"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --no-such-option", 2, {"--no-such-option"}},
    {"bond", "{packing.h5} -o {packing.h5}", 2, {"-o", "packing.h5"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --json {packing.h5}", 2, {"--json", "packing.h5"}},
    {"bond", "{packing.h5} -o {text:notadir}/b.h5", 2, {"notadir/b.h5"}},
    {"bond", "{packing.h5} -o {link:packing.h5}", 2, {"-o", "link-packing.h5"}},
    {"bond", "{packing.h5} -o {W}/./packing.h5", 2, {"-o", "packing.h5"}},
    // Hostile review D5: an option of another rule is refused, not ignored (overlap is the default).
    {"bond", "{packing.h5} -o {W}/b.h5 --target-density 0.7", 2, {"--target-density", "0.7", "--rule density"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --rule overlap --neck-ratio 0.3", 2, {"--neck-ratio", "0.3", "--rule ratio"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --pair-ratio a:a=0.3", 2, {"--pair-ratio", "--rule ratio"}},
    {"bond", "{packing.h5} -o {W}/b.h5 --rule ratio --sinter-config {sinter.yaml}", 2, {"--sinter-config", "--rule sinter"}},

    // ---- tomodem-young: bonded packing -> E, nu
    {"young", "{missing:bonded.h5}", 2, {"bonded.h5"}},
    {"young", "{empty:bonded.h5}", 2, {"bonded.h5"}},
    {"young", "{dir:bonded.h5}", 2, {"bonded.h5", "folder|directory"}},
    {"young", "{text:bonded.h5}", 2, {"bonded.h5"}},
    {"young", "{half:bonded.h5}", 2, {"bonded.h5"}},
    {"young", "{packing.h5}", 2, {"packing.h5", "/bonds"}},
    {"young", "{bonded.h5} --youngs-modulus nan", 2, {"--youngs-modulus", "nan"}},
    {"young", "{bonded.h5} --youngs-modulus -1", 2, {"--youngs-modulus", "-1"}},
    {"young", "{bonded.h5} --poisson-ratio 0.6", 2, {"--poisson-ratio", "0.6"}},
    {"young", "{bonded.h5} --density inf", 2, {"--density", "inf"}},
    {"young", "{bonded.h5} --tolerance 0", 2, {"--tolerance", "0"}},
    {"young", "{bonded.h5} --method nosuch", 2, {"--method", "nosuch"}},
    {"young", "{bonded.h5} --axis w", 2, {"--axis", "w"}},
    {"young", "{bonded.h5} --method explicit --strain nan", 2, {"--strain", "nan"}},
    {"young", "{bonded.h5} --method explicit --points 0", 2, {"--points", "0"}},
    {"young", "{bonded.h5} --method explicit --max-steps -1", 2, {"--max-steps", "-1"}},
    {"young", "{bonded.h5} --no-such-option", 2, {"--no-such-option"}},
    {"young", "{bonded.h5} --json {bonded.h5}", 2, {"--json", "bonded.h5"}},
    {"young", "{bonded.h5} --method explicit --curve {bonded.h5}", 2, {"--curve", "bonded.h5"}},
    {"young", "{bonded.h5} --json {text:notadir}/y.json", 2, {"notadir/y.json"}},
    {"young", "{bonded.h5} --json {W}/./bonded.h5", 2, {"--json", "bonded.h5"}},

    // ---- tomodem-fracture: bonded packing -> K_IC
    {"fracture", "{missing:bonded.h5}", 2, {"bonded.h5"}},
    {"fracture", "{empty:bonded.h5}", 2, {"bonded.h5"}},
    {"fracture", "{dir:bonded.h5}", 2, {"bonded.h5", "folder|directory"}},
    {"fracture", "{text:bonded.h5}", 2, {"bonded.h5"}},
    {"fracture", "{half:bonded.h5}", 2, {"bonded.h5"}},
    {"fracture", "{packing.h5}", 2, {"packing.h5", "/bonds"}},
    {"fracture", "{bonded.h5} --a-over-w nan", 2, {"--a-over-w", "nan"}},
    {"fracture", "{bonded.h5} --a-over-w 1.5", 2, {"--a-over-w", "1.5"}},
    {"fracture", "{bonded.h5} --fracture-energy -1", 2, {"--fracture-energy", "-1"}},
    {"fracture", "{bonded.h5} --criterion stress --tensile-strength nan", 2, {"--tensile-strength", "nan"}},
    {"fracture", "{bonded.h5} --method nosuch", 2, {"--method", "nosuch"}},
    {"fracture", "{bonded.h5} --geometry nosuch", 2, {"--geometry", "nosuch"}},
    {"fracture", "{bonded.h5} --max-breaks -1", 2, {"--max-breaks", "-1"}},
    {"fracture", "{bonded.h5} --youngs-modulus 0", 2, {"--youngs-modulus", "0"}},
    {"fracture", "{bonded.h5} --stop-fraction inf", 2, {"--stop-fraction", "inf"}},
    {"fracture", "{bonded.h5} --method explicit --timestep-fraction 0", 2, {"--timestep-fraction", "0"}},
    {"fracture", "{bonded.h5} --no-such-option", 2, {"--no-such-option"}},
    {"fracture", "{bonded.h5} --json {bonded.h5}", 2, {"--json", "bonded.h5"}},
    {"fracture", "{bonded.h5} --map {bonded.h5}", 2, {"--map", "bonded.h5"}},
    {"fracture", "{bonded.h5} --curve {text:notadir}/c.csv", 2, {"notadir/c.csv"}},
    {"fracture", "{bonded.h5} --curve {link:bonded.h5}", 2, {"--curve", "link-bonded.h5"}},

    // ---- tomodem-conduct: packing -> effective conductivity
    {"conduct", "{missing:bonded.h5}", 2, {"bonded.h5"}},
    {"conduct", "{empty:bonded.h5}", 2, {"bonded.h5"}},
    {"conduct", "{dir:bonded.h5}", 2, {"bonded.h5", "folder|directory"}},
    {"conduct", "{text:bonded.h5}", 2, {"bonded.h5"}},
    {"conduct", "{half:bonded.h5}", 2, {"bonded.h5"}},
    {"conduct", "{pack.yaml}", 2, {"pack.yaml"}},
    {"conduct", "{bonded.h5} --voltage nan", 2, {"--voltage", "nan"}},
    {"conduct", "{bonded.h5} --voltage inf", 2, {"--voltage", "inf"}},
    {"conduct", "{bonded.h5} --tolerance -1", 2, {"--tolerance", "-1"}},
    // Looser than 1e-3 the starting potential can pass with no iteration: no error estimate.
    {"conduct", "{bonded.h5} --tolerance 0.01", 2, {"--tolerance", "0.01", "0.001"}},
    {"conduct", "{bonded.h5} --gap-tolerance nan", 2, {"--gap-tolerance", "nan"}},
    {"conduct", "{bonded.h5} --bc nosuch", 2, {"--bc", "nosuch"}},
    {"conduct", "{bonded.h5} --axis q", 2, {"--axis", "q"}},
    {"conduct", "{bonded.h5} --preconditioner nosuch", 2, {"--preconditioner", "nosuch"}},
    {"conduct", "{bonded.h5} --phases nosuch", 2, {"--phases", "nosuch"}},
    {"conduct", "{bonded.h5} --voxel-check 100000", 2, {"--voxel-check", "100000"}},
    {"conduct", "{bonded.h5} --no-such-option", 2, {"--no-such-option"}},
    {"conduct", "{bonded.h5} -o {bonded.h5}", 2, {"-o", "bonded.h5"}},
    {"conduct", "{bonded.h5} --json {bonded.h5}", 2, {"--json", "bonded.h5"}},
    {"conduct", "{bonded.h5} -o {text:notadir}/c.h5", 2, {"notadir/c.h5"}},
    {"conduct", "{bonded.h5} --json {link:bonded.h5}", 2, {"--json", "link-bonded.h5"}},

    // ---- tomodem-carve: packing + macropores -> carved packing
    {"carve", "{missing:packing.h5} --level-set {pores.vdb} -o {W}/c.h5", 2, {"packing.h5"}},
    {"carve", "{empty:packing.h5} --level-set {pores.vdb} -o {W}/c.h5", 2, {"packing.h5"}},
    {"carve", "{half:packing.h5} --level-set {pores.vdb} -o {W}/c.h5", 2, {"packing.h5"}},
    {"carve", "{dir:packing.h5} --level-set {pores.vdb} -o {W}/c.h5", 2, {"packing.h5", "folder|directory"}},
    {"carve", "{packing.h5} --level-set {missing:pores.vdb} -o {W}/c.h5", 2, {"pores.vdb"}},
    // Hostile review D5: an option of another rule, method or source is refused, not ignored.
    {"carve", "{packing.h5} --level-set {pores.vdb} --fraction 0.2 -o {W}/c.h5", 2, {"--fraction", "0.2", "--rule fraction"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} --rule fraction --samples 3 -o {W}/c.h5", 2, {"--samples", "3", "sample"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} --label-values 7 -o {W}/c.h5", 2, {"--label-values", "7", "--labels"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} --spacing 1um -o {W}/c.h5", 2, {"--spacing", "1um", "--labels"}},
    {"carve", "{packing.h5} --labels {labels.h5} --grid foo -o {W}/c.h5", 2, {"--grid", "foo", "--level-set"}},
    {"carve", "{packing.h5} --level-set {empty:pores.vdb} -o {W}/c.h5", 2, {"pores.vdb"}},
    {"carve", "{packing.h5} --level-set {text:pores.vdb} -o {W}/c.h5", 2, {"pores.vdb"}},
    {"carve", "{packing.h5} --level-set {half:pores.vdb} -o {W}/c.h5", 2, {"pores.vdb"}},
    {"carve", "{packing.h5} --labels {half:labels.h5} -o {W}/c.h5", 2, {"labels.h5"}},
    {"carve", "{packing.h5} --labels {text:labels.h5} -o {W}/c.h5", 2, {"labels.h5"}},
    {"carve", "{packing.h5} --mesh {text:pore.off} -o {W}/c.h5", 2, {"pore.off"}},
    {"carve", "{packing.h5} --mesh {half:pore.off} -o {W}/c.h5", 2, {"pore.off"}},
    {"carve", "{packing.h5} -o {W}/c.h5", 2, {"--level-set"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --scale nan", 2, {"--scale", "nan"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --scale -1", 2, {"--scale", "'-1'"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --rule fraction --fraction nan", 2, {"--fraction", "nan"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --offset nan,0,0", 2, {"--offset", "nan"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --image-unit -1mm", 2, {"--image-unit", "-1mm"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --target-grid 100000", 2, {"--target-grid", "100000"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --relax -1", 2, {"--relax", "-1"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --no-such-option", 2, {"--no-such-option"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {packing.h5}", 2, {"-o", "packing.h5"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {W}/c.h5 --json {pores.vdb}", 2, {"--json", "pores.vdb"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {text:notadir}/c.h5", 2, {"notadir/c.h5"}},
    {"carve", "{packing.h5} --level-set {pores.vdb} -o {link:pores.vdb}", 2, {"-o", "link-pores.vdb"}},

    // ---- tomodem-dem: scene YAML -> packing, series
    {"dem", "{missing:scene.yaml} --output-dir {W}/out", 2, {"scene.yaml"}},
    {"dem", "{empty:scene.yaml} --output-dir {W}/out", 2, {"scene.yaml"}},
    {"dem", "{dir:scene.yaml} --output-dir {W}/out", 2, {"scene.yaml", "folder|directory"}},
    {"dem", "{text:scene.yaml} --output-dir {W}/out", 2, {"scene.yaml"}},
    {"dem", "{bin:scene.yaml} --output-dir {W}/out", 2, {"scene.yaml"}},
    {"dem", "{half:scene.yaml} --output-dir {W}/out", 2, {"scene.yaml"}},
    {"dem", "{packing.h5} --output-dir {W}/out", 2, {"packing.h5"}},
    {"dem", "{edit:scene.yaml:cells: 2=>cells: 100000} --output-dir {W}/out", 2, {"scene.yaml", "cells", "100000"}},
    {"dem", "{edit:scene.yaml:radius: 0.5e-3=>radius: .nan} --output-dir {W}/out", 2, {"scene.yaml", "radius", "nan"}},
    {"dem", "{edit:scene.yaml:density: 2500=>density: -2500} --output-dir {W}/out", 2, {"scene.yaml", "density", "-2500"}},
    {"dem", "{edit:scene.yaml:restitution: 0.5=>restitution: .inf} --output-dir {W}/out", 2, {"scene.yaml", "restitution", "inf"}},
    {"dem", "{edit:scene.yaml:steps: 20=>steps: 0} --output-dir {W}/out", 2, {"scene.yaml", "steps", "0"}},
    {"dem", "{scene_file.yaml} {!half:packing.h5} --output-dir {W}/out", 2, {"packing.h5"}},
    {"dem", "{scene_file.yaml} {!text:packing.h5} --output-dir {W}/out", 2, {"packing.h5"}},
    {"dem", "{edit:scene.yaml:packing: out.h5=>packing: ../scene.yaml} --output-dir {W}/out", 2, {"scene.yaml"}},
    {"dem", "{edit:scene_random.yaml:radius: 1.0e-4=>radius: 1.0e-12} --output-dir {W}/out", 2, {"scene_random.yaml", "protocol.timestep", "1.0e-7"}},
    {"dem", "{edit:scene_random.yaml:count: 50=>count: 1000000000000} --output-dir {W}/out", 2, {"scene_random.yaml", "count", "1000000000000"}},
    {"dem", "{edit:scene_random.yaml:upper: [2.0e-3=>upper: [-2.0e-3} --output-dir {W}/out", 2, {"scene_random.yaml", "cell", "-2.0e-3"}},
    {"dem", "{scene.yaml} --output-dir {W}/out --steps 0", 2, {"--steps", "0"}},
    {"dem", "{scene.yaml} --output-dir {W}/out --threads nan", 2, {"--threads", "nan"}},
    {"dem", "{scene.yaml} --output-dir {W}/out --restart {text:ck.h5}", 2, {"ck.h5"}},
    {"dem", "{scene.yaml} --output-dir {W}/out --restart {missing:ck.h5}", 2, {"ck.h5"}},
    {"dem", "{scene.yaml} --output-dir {W}/out --no-such-option", 2, {"--no-such-option"}},
    {"dem", "{scene.yaml} --output-dir {W}/out --json {scene.yaml}", 2, {"--json", "scene.yaml"}},
    {"dem", "{scene.yaml} --output-dir {text:notadir}", 2, {"notadir"}},
    {"dem", "{scene.yaml} --output-dir {W}/out --json {link:scene.yaml}", 2, {"--json", "link-scene.yaml"}},

    // ---- tomodem-sinter: sintering scene YAML
    {"sinter", "{missing:sinter.yaml} --output-dir {W}/out", 2, {"sinter.yaml"}},
    {"sinter", "{empty:sinter.yaml} --output-dir {W}/out", 2, {"sinter.yaml"}},
    {"sinter", "{dir:sinter.yaml} --output-dir {W}/out", 2, {"sinter.yaml", "folder|directory"}},
    {"sinter", "{text:sinter.yaml} --output-dir {W}/out", 2, {"sinter.yaml"}},
    {"sinter", "{bin:sinter.yaml} --output-dir {W}/out", 2, {"sinter.yaml"}},
    {"sinter", "{half:sinter.yaml} --output-dir {W}/out", 2, {"sinter.yaml"}},
    {"sinter", "{edit:sinter.yaml:relative_density: 0.78=>relative_density: 1.5} --output-dir {W}/out", 2, {"sinter.yaml", "relative_density", "1.5"}},
    {"sinter", "{edit:sinter.yaml:rate: 50=>rate: .nan} --output-dir {W}/out", 2, {"sinter.yaml", "rate", "nan"}},
    {"sinter", "{edit:sinter.yaml:boundary_diffusion: 8.6e-10=>boundary_diffusion: -1} --output-dir {W}/out", 2, {"sinter.yaml", "boundary_diffusion", "-1"}},
    {"sinter", "{edit:sinter.yaml:hold: 5000=>hold: .inf} --output-dir {W}/out", 2, {"sinter.yaml", "hold", "inf"}},
    {"sinter", "{edit:sinter.yaml:atomic_volume: 8.47e-30=>atomic_volume: 0} --output-dir {W}/out", 2, {"sinter.yaml", "atomic_volume", "0"}},
    {"sinter", "{edit:sinter.yaml:dihedral_angle: 150=>dihedral_angle: 200} --output-dir {W}/out", 2, {"sinter.yaml", "dihedral_angle", "200"}},
    {"sinter", "{edit:sinter.yaml:cells: 2=>cells: 100000} --output-dir {W}/out", 2, {"sinter.yaml", "cells", "100000"}},
    {"sinter", "{edit:sinter.yaml:start: 300=>start: -300} --output-dir {W}/out", 2, {"sinter.yaml", "start", "-300"}},
    {"sinter", "{sinter.yaml} --output-dir {W}/out --threads -1", 2, {"--threads", "-1"}},
    {"sinter", "{sinter.yaml} --output-dir {W}/out --no-such-option", 2, {"--no-such-option"}},
    {"sinter", "{sinter.yaml} --output-dir {W}/out --json {sinter.yaml}", 2, {"--json", "sinter.yaml"}},
    {"sinter", "{sinter.yaml} --output-dir {text:notadir}", 2, {"notadir"}},
    {"sinter", "{sinter.yaml} --output-dir {W}/out --json {link:sinter.yaml}", 2, {"--json", "link-sinter.yaml"}},

    // ---- tomodem-run: pipeline YAML
    {"run", "{missing:pipe.yaml}", 2, {"pipe.yaml"}},
    {"run", "{empty:pipe.yaml}", 2, {"pipe.yaml"}},
    {"run", "{dir:pipe.yaml}", 2, {"pipe.yaml", "folder|directory"}},
    {"run", "{text:pipe.yaml}", 2, {"pipe.yaml"}},
    {"run", "{bin:pipe.yaml}", 2, {"pipe.yaml"}},
    {"run", "{half:pipe.yaml}", 2, {"pipe.yaml"}},
    {"run", "{edit:pipe.yaml:outs: [out.txt]=>outs: [pipe.yaml]}", 2, {"pipe.yaml"}},
    {"run", "{edit:pipe.yaml:steps:=>bogus: 1\nsteps:}", 2, {"pipe.yaml", "bogus"}},
    {"run", "{edit:pipe.yaml:threads: 1=>threads: .nan}", 2, {"pipe.yaml", "threads", "nan"}},
    {"run", "{edit:pipe.yaml:threads: 1=>threads: -1}", 2, {"pipe.yaml", "threads", "-1"}},
    {"run", "{pipe.yaml} --jobs 0", 2, {"--jobs", "0"}},
    {"run", "{pipe.yaml} --jobs nan", 2, {"--jobs", "nan"}},
    {"run", "{pipe.yaml} --shard 5/2", 2, {"--shard", "5/2"}},
    {"run", "{pipe.yaml} --force nosuch", 2, {"nosuch"}},
    {"run", "{pipe.yaml} --set nosuch=1", 2, {"nosuch"}},
    {"run", "{pipe.yaml} --no-such-option", 2, {"--no-such-option"}},
    {"run", "{pipe.yaml} --json {pipe.yaml}", 2, {"--json", "pipe.yaml"}},
    {"run", "{pipe.yaml} --json {link:pipe.yaml}", 2, {"--json", "link-pipe.yaml"}},
    {"run", "{pipe.yaml} --json {text:notadir}/s.json", 2, {"--json", "notadir/s.json"}},
    {"run", "explain {pipe.yaml} nosuch", 2, {"nosuch"}},
    {"run", "row -o {W}/r.json --summary x={missing:s.json}", 2, {"s.json"}},
    {"run", "row -o {W}/r.json --summary x={text:s.json}", 2, {"s.json"}},
    {"run", "row -o {W}/r.json --value nonsense", 2, {"nonsense"}},
    {"run", "report -o {W}/rep {text:row.json}", 2, {"row.json"}},
    {"run", "report -o {W}/rep {missing:row.json}", 2, {"row.json"}},
    {"run", "report -o {W} {row.json}", 2, {"-o"}},
};

// ---------------------------------------------------------------------------------------------
// Valid inputs, made once (under a lock: ctest may run rows in parallel) and cached.
// ---------------------------------------------------------------------------------------------
const std::string kBin = TOMODEM_BIN_DIR;
const std::string kCache = (fs::path(TOMODEM_BUILD_DIR) / "tests/e2e/badinput/inputs").string();

const char* kPackYaml = R"(# a small green body (docs/pack.md)
particles: 150
seed: 1
phases:
  - name: ceramic
    material: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 6000, conductivity: 1.0e4, surface_energy: 1.0}
    size_distribution: {kind: lognormal, diameter: 5.0e-5, sigma: 0.2, basis: volume}
contact: {normal: hertz, friction: 0.3, restitution: 0.3}
target: {solid_fraction: 0.6}
output: {packing: packing.h5}
)";

const char* kSceneYaml = R"(# a small periodic FCC packing (docs/dem.md)
materials:
  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}
particles:
  generate: {arrangement: fcc, cells: 2, radius: 0.5e-3, solid_fraction: 0.7, velocity: 0.05, seed: 3, phase: glass}
physics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}
protocol: {timestep: auto, steps: 20, output_interval: 10}
output: {packing: out.h5, series: series.csv}
)";

const char* kSceneFileYaml = R"(# the particles of a packing file (docs/dem.md)
materials:
  - {name: ceramic, youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 6000}
particles: {file: packing.h5}
physics: {normal: hertz}
protocol: {timestep: auto, steps: 20}
output: {packing: out.h5, series: series.csv}
)";

const char* kSceneRandomYaml = R"(# random sequential insertion in a box between walls (docs/dem.md)
materials:
  - {name: sand, youngs_modulus: 7.0e10, poisson_ratio: 0.2, density: 2650}
particles:
  generate: {arrangement: random, count: 50, radius: 1.0e-4, seed: 7, phase: sand}
cell: {lower: [0, 0, 0], upper: [2.0e-3, 2.0e-3, 2.0e-3], periodic: [true, true, false]}
physics: {normal: linear, normal_stiffness: 1.0e4, restitution: 0.3, gravity: [0, 0, -9.81]}
walls:
  - {point: [0, 0, 0], normal: [0, 0, 1]}
protocol: {timestep: 1.0e-7, steps: 20}
output: {packing: out.h5, series: series.csv}
)";

const char* kSinterYaml = R"(# 32 alumina spheres heated and held (docs/sintering.md)
materials:
  - {name: alumina, youngs_modulus: 380.0e9, poisson_ratio: 0.22, density: 3950, surface_energy: 1.0}
particles:
  generate: {arrangement: fcc, cells: 2, radius: 1.0e-6, spacing: 2.82277e-6, jitter: 0.01, seed: 3, phase: alumina}
physics: {normal: sintering}
sintering:
  temperature:
    start: 300
    segments: [{rate: 50, to: 1600}, {hold: 5000}]
  phases:
    - {material: alumina, atomic_volume: 8.47e-30, boundary_diffusion: 8.6e-10, activation_energy: 418.0e3, dihedral_angle: 150}
  stop: {relative_density: 0.78}
)";

const char* kPipeYaml = R"(# one shell step (docs/pipelines.md)
steps:
  a:
    cmd: echo hi > ${outs.0}
    threads: 1
    outs: [out.txt]
)";

// A closed cube, 0.2 mm on a side, about the cell centre (OFF).
const char* kPoreOff = R"(OFF
8 12 0
-1e-4 -1e-4 -1e-4
1e-4 -1e-4 -1e-4
1e-4 1e-4 -1e-4
-1e-4 1e-4 -1e-4
-1e-4 -1e-4 1e-4
1e-4 -1e-4 1e-4
1e-4 1e-4 1e-4
-1e-4 1e-4 1e-4
3 0 2 1
3 0 3 2
3 4 5 6
3 4 6 7
3 0 1 5
3 0 5 4
3 2 3 7
3 2 7 6
3 1 2 6
3 1 6 5
3 0 4 7
3 0 7 3
)";

const char* kRowJson = R"({"x": 1, "y": 2.5}
)";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
void spit(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

int shell(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/// The cache is stale when the tools that make it, or this test, are newer than its stamp.
bool cache_fresh() {
  const fs::path stamp = fs::path(kCache) / "stamp";
  std::error_code ec;
  const auto t = fs::last_write_time(stamp, ec);
  if (ec) return false;
  std::vector<fs::path> makers = {fs::read_symlink("/proc/self/exe", ec)};
  for (const char* t : {"pack", "bond", "phantom", "segment"}) makers.push_back(kBin + "/tomodem-" + t);
  for (const auto& m : makers) {
    std::error_code e2;
    const auto tm = fs::last_write_time(m, e2);
    if (!e2 && tm > t) return false;
  }
  return true;
}

/// Makes the cached inputs; returns the log of the commands that failed ("" when all worked).
std::string make_cache() {
  const fs::path c = kCache;
  fs::create_directories(c);
  const int lock = ::open((c / ".lock").c_str(), O_CREAT | O_RDWR, 0644);
  ::flock(lock, LOCK_EX);
  std::string failures;
  if (!cache_fresh()) {
    for (const auto& e : fs::directory_iterator(c))
      if (e.path().filename() != ".lock") fs::remove_all(e.path());
    spit(c / "pack.yaml", kPackYaml);
    spit(c / "scene.yaml", kSceneYaml);
    spit(c / "scene_file.yaml", kSceneFileYaml);
    spit(c / "scene_random.yaml", kSceneRandomYaml);
    spit(c / "sinter.yaml", kSinterYaml);
    spit(c / "pipe.yaml", kPipeYaml);
    spit(c / "pore.off", kPoreOff);
    spit(c / "row.json", kRowJson);
    const std::string cd = "cd '" + c.string() + "' && OMP_NUM_THREADS=1 ";
    const std::vector<std::string> cmds = {
        kBin + "/tomodem-pack pack.yaml -o packing.h5 --no-tessellation -q",
        kBin + "/tomodem-bond packing.h5 -o bonded.h5 --rule ratio --neck-ratio 0.1 --gap-tolerance 0.05 -q",
        kBin + "/tomodem-phantom --kind pores --size 32 --macropores 2 --seed 3 -o grey.mha --truth truth.h5 -q",
        kBin + "/tomodem-phantom --kind pores --size 32 --macropores 2 --seed 3 -o grey.tif -q",
        kBin + "/tomodem-segment grey.mha --macropore-radius 2vox -o labels.h5 --vdb pores.vdb -q"};
    for (const auto& cmd : cmds)
      if (shell(cd + cmd + " > make.log 2>&1") != 0) failures += cmd + ":\n" + slurp(c / "make.log") + "\n";
    fs::remove(c / "make.log");
    // side files of the makers (xdmf sidecars) are not inputs of the rows
    if (failures.empty()) spit(c / "stamp", "ok\n");
    else spit(c / "failures.log", failures);
  } else if (fs::exists(c / "failures.log")) {
    failures = slurp(c / "failures.log");
  }
  ::flock(lock, LOCK_UN);
  ::close(lock);
  return failures;
}

const std::string& cache_failures() {
  static const std::string f = make_cache();
  return f;
}

// ---------------------------------------------------------------------------------------------
// One row: expand the placeholders, run, compare the folder before and after.
// ---------------------------------------------------------------------------------------------
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
  return s;
}

/// Every file and folder under `dir` (relative path -> content; folders map to "<dir>").
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> m;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string rel = fs::relative(e.path(), dir).string();
    if (e.is_directory()) m[rel] = "<dir>";
    else if (e.is_symlink()) m[rel] = "<link>";
    else m[rel] = slurp(e.path());
  }
  return m;
}

std::string binary_junk() {
  std::string s;
  unsigned x = 12345;
  for (int k = 0; k < 4096; ++k) {
    x = x * 1103515245u + 12345u;
    s.push_back(char((x >> 16) & 0xFF));
  }
  s[0] = '\0';
  s[1] = char(0xFF);
  return s;
}

/// Creates W/name for one placeholder; returns an error text ("" when done).
std::string make_input(const fs::path& w, const std::string& kind, const std::string& spec) {
  std::string name = spec;
  if (kind == "edit") name = spec.substr(0, spec.find(':'));
  const fs::path dst = w / name;
  const fs::path src = fs::path(kCache) / name;
  if (kind == "link") {  // link-NAME -> NAME (made by another placeholder)
    if (!fs::exists(w / ("link-" + name))) fs::create_symlink(name, w / ("link-" + name));
    return fs::exists(dst) ? "" : "link to " + name + ", which no placeholder before it made";
  }
  if (fs::exists(dst) || kind == "missing") return "";
  if (kind == "empty") spit(dst, "");
  else if (kind == "dir") fs::create_directories(dst);
  else if (kind == "text") spit(dst, "This is a plain text file, not the kind of file this option expects.\nline two\n");
  else if (kind == "bin") spit(dst, binary_junk());
  else {
    if (!fs::exists(src)) return "no cached input " + name + " (its maker failed: see " + kCache + "/failures.log)";
    std::string data = slurp(src);
    if (kind == "half") {
      std::size_t cut = data.size() / 2;
      while (cut > 1 && cut < data.size() && (data[cut - 1] == '\n' || data[cut] == '\n')) ++cut;  // mid-line
      data.resize(cut);
    } else if (kind == "edit") {
      const std::string rule = spec.substr(name.size() + 1);
      const auto arrow = rule.find("=>");
      if (arrow == std::string::npos) return "edit without =>: " + spec;
      std::string from = rule.substr(0, arrow), to = rule.substr(arrow + 2);
      for (auto* s : {&from, &to})
        for (std::size_t k; (k = s->find("\\n")) != std::string::npos;) s->replace(k, 2, "\n");
      const auto at = data.find(from);
      if (at == std::string::npos) return "edit: '" + from + "' is not in " + name;
      data.replace(at, from.size(), to);
    } else if (kind != "copy") {
      return "unknown placeholder kind " + kind;
    }
    spit(dst, data);
  }
  return "";
}

/// Expands the placeholders of `args`, creating the inputs in w.
std::string expand(const std::string& args, const fs::path& w, std::string* error) {
  std::string out;
  for (std::size_t k = 0; k < args.size();) {
    if (args[k] != '{') {
      out += args[k++];
      continue;
    }
    const auto end = args.find('}', k);
    std::string p = args.substr(k + 1, end - k - 1);
    k = end + 1;
    const bool silent = !p.empty() && p[0] == '!';
    if (silent) p.erase(0, 1);
    if (p == "W") {
      out += w.string();
      continue;
    }
    std::string kind = "copy", spec = p;
    const auto colon = p.find(':');
    if (colon != std::string::npos) kind = p.substr(0, colon), spec = p.substr(colon + 1);
    const std::string e = make_input(w, kind, spec);
    if (!e.empty()) *error += e + "\n";
    if (!silent)
      out += (w / (kind == "edit" ? spec.substr(0, spec.find(':')) : kind == "link" ? "link-" + spec : spec)).string();
  }
  return out;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

/// Splits on spaces outside placeholders, so that an edit may hold spaces.
std::vector<std::string> words(const std::string& args) {
  std::vector<std::string> w;
  std::string cur;
  int depth = 0;
  for (char ch : args) {
    if (ch == '{') ++depth;
    if (ch == '}') --depth;
    if (ch == ' ' && depth == 0) {
      if (!cur.empty()) w.push_back(cur), cur.clear();
    } else {
      cur += ch;
    }
  }
  if (!cur.empty()) w.push_back(cur);
  return w;
}

class CrossToolBadInput : public ::testing::TestWithParam<std::size_t> {};

TEST_P(CrossToolBadInput, Row) {
  const Row& row = kRows[GetParam()];
  const std::string exe = kBin + "/tomodem-" + row.tool;
  if (!fs::exists(exe)) GTEST_SKIP() << exe << " is not part of this build";
  // TOMODEM_BADINPUT_RUN_OPEN=1 runs the open rows too (to see which ones a fix has closed).
  if (*row.open && !std::getenv("TOMODEM_BADINPUT_RUN_OPEN")) GTEST_SKIP() << "open: " << row.open;
  const fs::path base = fs::temp_directory_path() / ("tomodem-badinput-" + std::to_string(::getpid()) + "-" +
                                                     std::to_string(GetParam()));
  fs::remove_all(base);
  const fs::path w = base / "work";
  fs::create_directories(w);
  (void)cache_failures();

  std::string error, cmd = "cd " + quote(w.string()) + " && OMP_NUM_THREADS=1 timeout 120 " + quote(exe);
  {
    // Copy under a shared lock: another ctest process may be remaking a stale cache.
    const int lock = ::open((fs::path(kCache) / ".lock").c_str(), O_CREAT | O_RDWR, 0644);
    ::flock(lock, LOCK_SH);
    for (const auto& word : words(row.args)) {
      const std::string arg = expand(word, w, &error);
      if (!(arg.empty() && word.rfind("{!", 0) == 0)) cmd += " " + quote(arg);  // {!..} stands for nothing
    }
    ::flock(lock, LOCK_UN);
    ::close(lock);
  }
  ASSERT_TRUE(error.empty()) << error;
  const auto before = snapshot(w);
  const int st = std::system((cmd + " > " + quote((base / "stdout").string()) + " 2> " +
                              quote((base / "stderr").string())).c_str());
  const int code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  const std::string err = slurp(base / "stderr");
  const std::string context = "tomodem-" + std::string(row.tool) + " " + row.args + "\n$ " + cmd + "\nstderr:\n" + err;

  if (std::getenv("TOMODEM_BADINPUT_VERBOSE")) {
    std::string last = err.substr(0, err.find_last_not_of('\n') + 1);
    last = last.substr(last.find_last_of('\n') + 1);
    std::cout << "[ row ] " << row.tool << " " << row.args << "\n        -> " << code << ": " << last << std::endl;
  }
  EXPECT_EQ(code, row.code) << context;
  for (const auto& n : row.names) {  // "a|b": either
    bool found = false;
    for (std::size_t b = 0, e; b <= n.size(); b = e + 1) {
      e = std::min(n.find('|', b), n.size());
      found = found || lower(err).find(lower(n.substr(b, e - b))) != std::string::npos;
    }
    EXPECT_TRUE(found) << "stderr does not name '" << n << "'\n" << context;
  }
  const auto after = snapshot(w);
  for (const auto& [path, content] : after) {
    const auto it = before.find(path);
    EXPECT_TRUE(it != before.end()) << "left behind: " << path << "\n" << context;
    if (it != before.end()) EXPECT_TRUE(it->second == content) << "changed: " << path << "\n" << context;
  }
  for (const auto& [path, content] : before)
    EXPECT_TRUE(after.count(path)) << "removed: " << path << "\n" << context;
  if (!HasFailure()) fs::remove_all(base);
}

std::string row_name(const ::testing::TestParamInfo<std::size_t>& info) {
  const std::string tool = kRows[info.param].tool;
  int k = 0;
  for (std::size_t i = 0; i < info.param; ++i) k += tool == kRows[i].tool;
  char buf[8];
  std::snprintf(buf, sizeof buf, "%02d", k + 1);
  return tool + "_" + buf;
}

INSTANTIATE_TEST_SUITE_P(AllTools, CrossToolBadInput, ::testing::Range<std::size_t>(0, kRows.size()), row_name);

}  // namespace
