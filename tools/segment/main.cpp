// tomodem-segment: X-ray tomography volume -> phases, macropores, grains (docs/segment.md).
#include <CLI/CLI.hpp>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/cli_choice.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/image/segment.hpp"
#include "tomodem/image/tools.hpp"

// Unsigned options: CLI11 would wrap "-4" round to 18446744073709551612; refuse it as written.
const CLI::Validator non_negative(
    [](std::string& s) { return s.find('-') != std::string::npos ? "must be >= 0, not " + s : std::string(); }, "INT>=0");

int main(int argc, char** argv) {
  return tomodem::run_tool("tomodem-segment", [&]() -> int {
    tomodem::image::SegmentConfig c;
    CLI::App app{"Segment a tomography volume into solid, fine pores and macropores (docs/segment.md)", "tomodem-segment"};
    app.add_option("input", c.input, "volume: file, folder of TIFF slices or of a DICOM series, or a pattern (slices sorted by name)")->required();
    tomodem::cli::add_choice(app, "--format", c.read.format, tomodem::image::kVolumeFormatNames, "auto | tiff | mha | nrrd | nifti | raw | h5 | dicom (a folder with one series)");
    app.add_option("--spacing", c.spacing_text,
                   "voxel size, one length or x,y,z (60.7um, 1um,1um,2um; lengths: m, mm, um, nm; bare numbers: m); overrides the header");
    tomodem::cli::add_length(app, "--header-unit", c.read.header_unit,
                             "length of one unit of MetaImage/NRRD/NIfTI headers (default 1mm)");
    app.add_option("--raw-dims", c.raw_dims_text, "raw: NX,NY,NZ");
    tomodem::cli::add_choice(app, "--raw-type", c.read.raw_type, tomodem::image::kRawTypeNames,
                             "raw: uint8 | int8 | uint16 | int16 | uint32 | int32 | float32 | float64");
    tomodem::cli::add_choice(app, "--byte-order", c.read.byte_order, tomodem::image::kByteOrderNames, "raw: little | big");
    app.add_option("--raw-header", c.read.raw_header, "raw: bytes to skip")->capture_default_str()
        ->check(non_negative);
    app.add_option("--dataset", c.read.h5_dataset, "HDF5 dataset (z, y, x)")->capture_default_str();
    app.add_option("--roi", c.roi_text, "crop X0,Y0,Z0,NX,NY,NZ (voxels)");
    app.add_option("--downsample", c.read.downsample, "block-average by this integer factor")->capture_default_str();
    tomodem::cli::add_choice(app, "--filter", c.filter, tomodem::image::kImageFilterNames, "none | median | gaussian | cad | nlm");
    app.add_option("--filter-radius", c.filter_radius_text,
                   "median radius / NLM patch radius: voxels of the finest axis (2vox) or a length (2um), the same length on every axis; a bare number is refused")
        ->capture_default_str();
    app.add_option("--sigma", c.sigma_text, "gaussian sigma: voxels of the finest axis (1.5vox) or a length (1.5um); a bare number is refused")->capture_default_str();
    app.add_option("--iterations", c.iterations, "cad / nlm iterations")->capture_default_str();
    app.add_option("--conductance", c.conductance, "cad conductance")->capture_default_str();
    tomodem::cli::add_choice(app, "--method", c.method, tomodem::image::kThresholdMethodNames,
                             "otsu | peaks | intermeans | multiotsu2 | multiotsu3 | manual | hysteresis");
    app.add_option("--levels", c.levels, "manual thresholds (1 or 2) or hysteresis LOW,HIGH (grey values)")->delimiter(',');
    app.add_flag("--pores-bright", c.pores_bright, "pores are brighter than the solid");
    app.add_option("--open", c.open_r, "open the solid with a ball of this radius (voxels)")->capture_default_str();
    app.add_option("--close", c.close_r, "close the solid with a ball of this radius (voxels)")->capture_default_str();
    app.add_option("--min-island", c.min_island, "remove solid and pore islands below this many voxels")->capture_default_str()
        ->check(non_negative);
    app.add_option("--connectivity", c.connectivity, "6 or 26 (islands)")->capture_default_str();
    app.add_option("--macropore-radius", c.macro_radius_text, "opening ball radius separating macropores (3vox, 50um)")
        ->capture_default_str();
    app.add_option("--macropore-min-voxels", c.macro_min_voxels, "drop macropores smaller than this")->capture_default_str()
        ->check(non_negative);
    app.add_flag("--grains", c.grains, "separate grains (distance map + h-maxima + watershed)");
    app.add_option("--h", c.h, "h-maxima height of the distance map (voxels)")->capture_default_str();
    app.add_option("--packing", c.packing, "write the grains as a packing (.h5, implies --grains)");
    app.add_option("-o,--output", c.output, "labels (.h5: /labels, /macropores, /grains)");
    app.add_option("--mha", c.mha, "labels as MetaImage (.mha or .mhd)");
    app.add_option("--vdb", c.vdb, "macropores as an OpenVDB signed-distance level set (world unit mm, stated in its metadata)");
    app.add_option("--overlay", c.overlay, "mid-plane PNG overlays: PREFIX_xy.png, _xz, _yz");
    app.add_option("--chunk", c.chunk, "out of core: process blocks of this many voxels per side with halos (raw or HDF5 input; docs/segment.md)")
        ->check(non_negative);
    app.add_option("--memory", c.memory_text, "out of core: memory budget (8GB, 512MB, 8GiB); the block size is chosen from it");
    tomodem::cli::Common common;
    tomodem::cli::add_common(app, "tomodem-segment", common);
    if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
    c.json = common.json;
    c.as_written = tomodem::image::options_as_written(app);
    tomodem::image::set_threads(common.threads);
    if (!c.packing.empty()) c.grains = true;
    tomodem::emit_summary(tomodem::image::run_segment(c), c.json);
    return tomodem::exit_code::ok;
  });
}
