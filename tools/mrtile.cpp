// The mrtile command-line tool: parses options into the library's option structs, runs the stages,
// and reports. It is the only place that prints and picks exit codes (0 ok, 1 error, 2 usage).
#include "formats/lod_tileset.h"
#include "formats/read_points.h"
#include "formats/write_3d_tiles.h"
#include "formats/write_gltf.h"
#include "formats/write_mesh.h"
#include "tools/huge_page_malloc.h"
#include "libmrtile/atomic_file.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/georef.h"
#include "libmrtile/lod_set.h"
#include "libmrtile/model_file.h"
#include "libmrtile/outliers.h"
#include "libmrtile/parallel.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/sample_dimension.h"
#include "libmrtile/shapes.h"
#include "libmrtile/single_view.h"
#include "libmrtile/union_find.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cassert>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

namespace {

// "1 tile", "2 tiles": counts as a reader says them (QA round 64: "1 levels", "1 boundary loops").
std::string count_of(std::size_t n, const char* one, const char* many)
{
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

// The length of the well-formed UTF-8 sequence at text[at] (RFC 3629: no overlong forms, surrogates or
// code points past U+10FFFF), or 0 when there is none.
std::size_t utf8_length(const std::string& text, std::size_t at)
{
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
    const unsigned char lead = byte(at);
    if (lead < 0x80)
        return 1;
    std::size_t length = 0;
    unsigned char low = 0x80, high = 0xBF; // the allowed range of the second byte
    if (lead >= 0xC2 && lead <= 0xDF)
        length = 2;
    else if (lead >= 0xE0 && lead <= 0xEF) {
        length = 3;
        low = lead == 0xE0 ? 0xA0 : 0x80;
        high = lead == 0xED ? 0x9F : 0xBF;
    } else if (lead >= 0xF0 && lead <= 0xF4) {
        length = 4;
        low = lead == 0xF0 ? 0x90 : 0x80;
        high = lead == 0xF4 ? 0x8F : 0xBF;
    } else
        return 0;
    if (at + length > text.size() || byte(at + 1) < low || byte(at + 1) > high)
        return 0;
    for (std::size_t k = 2; k < length; ++k)
        if (byte(at + k) < 0x80 || byte(at + k) > 0xBF)
            return 0;
    return length;
}

// A message printed on one line whatever it holds: a file name or an argument with a line break in it
// made an error of two lines (QA round 66), and `info` printed a LAS file's Latin-1 WKT name byte for
// byte (QA round 66). Control characters and bytes that are no UTF-8 become '?', as `ls` shows them.
std::string one_line(std::string text)
{
    for (std::size_t at = 0; at < text.size();) {
        const unsigned char c = static_cast<unsigned char>(text[at]);
        const std::size_t length = utf8_length(text, at);
        if (length == 0 || c < 0x20 || c == 0x7f) {
            text[at] = '?';
            ++at;
        } else
            at += length;
    }
    return text;
}

// CLI11's PositiveNumber / NonNegativeNumber print the whole double range when they fail; these say
// what is wanted in a few words.
CLI::Validator number_check(bool allow_zero)
{
    return CLI::Validator(
        [allow_zero](std::string& text) -> std::string {
            // Plain decimal numbers, as whole-number options take them: strtod also took " 5", "+5" and
            // "0x10" (16) but not "5 " (QA round 34).
            double v = 0.0;
            const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (error == std::errc::result_out_of_range && end == text.data() + text.size())
                return "'" + text + "' is out of the range of numbers (about 1e-308 to 1e308)";
            const bool ok = error == std::errc() && end == text.data() + text.size() && std::isfinite(v) &&
                            (allow_zero ? v >= 0 : v > 0);
            return ok ? std::string() : "'" + text + "' is not a number " + (allow_zero ? ">= 0" : "> 0");
        },
        allow_zero ? "NUMBER >= 0" : "NUMBER > 0");
}
const CLI::Validator kPositive = number_check(false);
const CLI::Validator kNonNegative = number_check(true);

// A comma-separated list of numbers >= 0, every item checked: CLI11's delimiter dropped empty items, so
// "0.1,,0.05" passed as two tolerances (QA round 29).
const CLI::Validator kNonNegativeList(
    [](std::string& text) {
        std::stringstream items(text + ",");
        std::string item;
        while (std::getline(items, item, ',')) {
            // Blanks around an item are allowed, as in the --focus and --camera lists ("0.02, 0.01").
            const std::size_t first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
            std::string copy = first == std::string::npos ? std::string() : item.substr(first, last - first + 1);
            if (std::string why = kNonNegative(copy); !why.empty())
                return why;
        }
        return std::string();
    },
    "NUMBER,NUMBER,...");

// Whole numbers in [lo, hi], written as digits: CLI11 would let "-1" wrap and 2^64 saturate in a size_t.
CLI::Validator integer_check(unsigned long long lo, unsigned long long hi)
{
    return CLI::Validator(
        [lo, hi](std::string& text) -> std::string {
            const bool digits = !text.empty() && text.size() <= 19 &&
                                std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
            const unsigned long long v = digits ? std::stoull(text) : 0;
            if (digits && v >= lo && v <= hi)
                return std::string();
            return "'" + text + "' is not a whole number from " + std::to_string(lo) + " to " + std::to_string(hi);
        },
        "INTEGER in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

// Whether an option appeared on the command line (its value alone cannot tell a default from a choice).
bool given(const CLI::Option* option) { return option != nullptr && option->count() > 0; }

// A coordinate as the fewest digits that read back as the same double (printf's %.17g showed
// 979993.34100000001 for 979993.341: QA round 48).
std::string shortest(double v)
{
    char text[32];
    const auto [end, error] = std::to_chars(text, text + sizeof text, v);
    return error == std::errc() ? std::string(text, end) : std::to_string(v);
}

// Three coordinates, as shortest gives them, separated by `between`.
std::string shortest(const mrt::Vec3& p, const char* between = " ")
{
    return shortest(p.x) + between + shortest(p.y) + between + shortest(p.z);
}

// A text option given as "" would read as not given at all; a path given as "" passed every check and
// failed after the work ("mrtile: error: : cannot rename temporary file into place", exit 1; `--model ''`
// saved no model without a word: QA round 29).
const CLI::Validator kNonEmpty(
    [](std::string& text) { return text.empty() ? std::string("must not be empty") : std::string(); }, "TEXT");

using namespace mrt;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Thrown for bad option values found after parsing (CLI11 handles the rest); exit code 2.
struct UsageError : std::runtime_error
{
    using std::runtime_error::runtime_error;
};

struct Globals
{
    bool quiet = false;
    bool below_noise = false; //!< cut below the nodes' noise floors
    bool progress() const { return !quiet && ::isatty(2); }
};

std::string lower_extension(const fs::path& p)
{
    std::string e = p.extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e;
}

std::vector<double> parse_numbers(const std::string& text, char separator, const std::string& what)
{
    std::vector<double> out;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, separator)) {
        try {
            std::size_t used = 0;
            const double v = std::stod(item, &used);
            if (used != item.size() || !std::isfinite(v))
                throw std::invalid_argument(item);
            out.push_back(v);
        } catch (const std::exception&) {
            throw UsageError(what + ": '" + item + "' is not a finite number");
        }
    }
    return out;
}

// --- options shared by several commands -------------------------------------------------------

struct BuildArgs
{
    double tolerance = BuildOptions{}.tolerance;
    double tau = 0.0;
    std::size_t pca_limit = BuildOptions{}.pca_limit;
    std::size_t min_cluster = BuildOptions{}.min_cluster;
    bool no_reclassify = false;
    bool remove_outliers = false;
    bool allow_volume = false;
    std::string denoise = "auto";
    bool keep_duplicates = false;
    bool skip_missing_scans = false;
    std::size_t max_points = 0;
    std::string viewpoint;
    std::string crs;

    // `build` names them --tolerance/--tau; `reconstruct` prefixes them (its --tolerance is the cut's).
    void add(CLI::App* cmd, const std::string& prefix)
    {
        auto* tol = cmd->add_option("--" + prefix + "tolerance", tolerance,
                                    "hierarchy stop criterion: RMS plane distance / largest bbox side")
                        ->check(kNonNegative)
                        ->capture_default_str();
        auto* t = cmd->add_option("--" + prefix + "tau", tau, "hierarchy stop criterion: the paper's tau (units^2)")
                      ->check(kPositive);
        tol->excludes(t);
        // The model stores it in 32 bits (QA round 34: larger values were saturated without a word).
        cmd->add_option("--pca-limit", pca_limit, "clusters up to this size split along the PCA axis")
            ->check(integer_check(0, std::numeric_limits<std::uint32_t>::max()))
            ->capture_default_str();
        // Below 8 points a leaf's plane fits a handful of points, and meshes of such leaves break into
        // hundreds of pieces (QA, session 17: 5 to 450 pieces for 1 to 6 on a clean sphere).
        cmd->add_option("--min-cluster", min_cluster, "clusters up to this size are not split (at least 8: smaller leaves fit no reliable plane)")
            ->check(integer_check(8, 1ull << 31))
            ->capture_default_str();
        cmd->add_flag("--no-reclassify", no_reclassify, "skip the Gabriel-neighbour reclassification");
        cmd->add_flag("--keep-duplicates", keep_duplicates, "do not merge points at exactly the same position");
        cmd->add_flag("--skip-missing-scans", skip_missing_scans,
                      "scan lists (.conf): read the scans that exist, leave out the missing ones");
        cmd->add_option("--max-points", max_points,
                        "refuse inputs that declare or hold more points than this, before reading them where a header "
                        "says how many (a service's bound on untrusted files; default: none)")
            ->check(integer_check(1, std::numeric_limits<std::uint32_t>::max()));
        cmd->add_option("--viewpoint", viewpoint,
                        "X,Y,Z where the scanner stood, for a single view (input coordinates): open surfaces face "
                        "it, and gap faces do not span space it saw through (default: from the file, as a PTX scan or a "
                        "PCD's VIEWPOINT tells it)")
            ->check(kNonEmpty);
        cmd->add_option("--crs", crs,
                        "coordinate system of the input: EPSG:N, WKT, or a .prj/.wkt file holding WKT (default: "
                        "from the file, as a LAS file tells it); 3D Tiles are placed on the globe by it")
            ->check(kNonEmpty);
        const OutlierOptions outliers;
        cmd->add_flag("--remove-outliers", remove_outliers,
                      "drop isolated points first (mean distance to " + std::to_string(outliers.neighbours) + " neighbours > " +
                          CLI::detail::to_string(outliers.local_ratio) + "x theirs or > " +
                          CLI::detail::to_string(outliers.global_ratio) + "x the cloud's median)");
        cmd->add_flag("--allow-volume", allow_volume,
                      "build from points that fill a volume instead of sampling a surface (refused otherwise, after "
                      "the build: their mesh takes minutes and is of no use)");
        cmd->add_option("--denoise", denoise,
                        "move each point onto a quadric fitted to it and its " + std::to_string(DenoiseOptions{}.neighbours - 1) +
                            " nearest neighbours and build again: auto (when the sample is noisy, about a point spacing or more), on, off")
            ->check(CLI::IsMember({"auto", "on", "off"}))
            ->capture_default_str();
    }

    BuildOptions options(const Globals& g) const
    {
        BuildOptions o;
        o.tolerance = tolerance;
        o.tau = tau;
        o.pca_limit = pca_limit;
        o.min_cluster = min_cluster;
        o.reclassify = !no_reclassify;
        o.merge_duplicates = !keep_duplicates;
        o.denoise = denoise == "on" ? BuildOptions::Denoise::On : denoise == "off" ? BuildOptions::Denoise::Off : BuildOptions::Denoise::Auto;
        if (g.progress())
            o.progress = [](const char* stage, double f) { std::fprintf(stderr, "\r%s %5.1f%%      ", stage, 100.0 * f); };
        return o;
    }
};

struct CutArgs
{
    double tolerance = -1.0; // not given: kDefaultTolerance; 0: the finest cut
    double error = -1.0;     // >= 0: the tolerance in model units (RMS plane distance), given instead
    double tau = 0.0;
    std::size_t tiles = 0;
    std::size_t triangles = 0;
    std::vector<std::string> focus;
    std::string camera;
    std::vector<CLI::Option*> options; // every cut option, to tell whether any was used

    static constexpr double kDefaultTolerance = 0.002;

    void add(CLI::App* cmd)
    {
        auto* tol = cmd->add_option("--tolerance", tolerance,
                                    "cut: RMS plane distance / largest bbox side (default 0.002; 0: the finest cut)")
                        ->check(kNonNegative);
        auto* err = cmd->add_option("--error", error,
                                    "cut: RMS plane distance in model units (metres for lidar): --tolerance E / the model's scale (0: the finest cut)")
                        ->check(kNonNegative);
        auto* t = cmd->add_option("--tau", tau, "cut: the paper's tau, smallest eigenvalue of M (units^2)")
                      ->check(kPositive);
        auto* n = cmd->add_option("--tiles", tiles, "cut: the best cut with N tiles")->check(integer_check(1, 1ull << 40));
        auto* tri = cmd->add_option("--triangles", triangles,
                                    "cut: the finest best-N cut whose mesh has at most this many triangles")
                        ->check(integer_check(1, 1ull << 40));
        tri->excludes(tol)->excludes(t)->excludes(n)->excludes(err);
        err->excludes(tol)->excludes(t)->excludes(n);
        auto* f = cmd->add_option("--focus", focus, "refine a sphere X,Y,Z,R[:TOL] (repeatable; TOL default 0)")
                      ->check(kNonEmpty);
        auto* c = cmd->add_option("--camera", camera, "view-dependent cut X,Y,Z:TX,TY,TZ:FOV:HEIGHT[:PIXELS] (camera at X,Y,Z looking at TX,TY,TZ; vertical FOV in degrees, viewport HEIGHT in pixels (16:9), PIXELS default 16: refines what is in view while its screen-space error exceeds PIXELS)")
                      ->check(kNonEmpty);
        tol->excludes(t)->excludes(n);
        t->excludes(n);
        // A focus refines a tolerance cut, and a camera makes its own: what they would ignore is refused.
        c->excludes(f)->excludes(n)->excludes(t)->excludes(tri)->excludes(err)->excludes(tol);
        f->excludes(tri)->excludes(n)->excludes(t);
        options = {tol, err, t, n, tri, f, c};
    }

    bool any_given() const
    {
        return std::any_of(options.begin(), options.end(), given);
    }

    // The camera as given (absolute coordinates). \throw UsageError for a malformed or meaningless one.
    Camera parsed_camera() const
    {
        std::vector<std::string> parts;
        std::stringstream ss(camera);
        std::string part;
        while (std::getline(ss, part, ':'))
            parts.push_back(part);
        if (parts.size() < 4 || parts.size() > 5)
            throw UsageError("--camera: expected X,Y,Z:TX,TY,TZ:FOV:HEIGHT[:PIXELS]");
        const auto p = parse_numbers(parts[0], ',', "--camera position");
        const auto target = parse_numbers(parts[1], ',', "--camera target");
        if (p.size() != 3 || target.size() != 3)
            throw UsageError("--camera: position and target need three coordinates each");
        auto one = [&](const std::string& text, const char* what) {
            const auto v = parse_numbers(text, ',', what);
            if (v.size() != 1)
                throw UsageError(std::string(what) + ": expected one number, got '" + text + "'");
            return v[0];
        };
        Camera cam;
        cam.position = Vec3{p[0], p[1], p[2]};
        cam.direction = Vec3{target[0], target[1], target[2]} - cam.position; // in view: what it looks at
        if (!(norm(cam.direction) > 0))
            throw UsageError("--camera: the target must differ from the position (it sets the view direction)");
        // Finite coordinates can still be too far apart for their difference (1e308 and -1e308): the cut
        // refused the infinite direction only after the model was loaded, as an error (exit 1).
        if (!std::isfinite(norm(cam.direction)))
            throw UsageError("--camera: the position and the target are too far apart (the view direction is not finite)");
        cam.fov_y_degrees = one(parts[2], "--camera fov");
        cam.viewport_height = one(parts[3], "--camera height");
        if (parts.size() == 5)
            cam.max_pixel_error = one(parts[4], "--camera pixels");
        if (!(cam.fov_y_degrees > 0 && cam.fov_y_degrees < 180))
            throw UsageError("--camera: the field of view must be between 0 and 180 degrees");
        if (!(cam.viewport_height > 0) || !(cam.max_pixel_error > 0))
            throw UsageError("--camera: the viewport height and the pixel error must be > 0");
        return cam;
    }

    // The focus regions as given (absolute coordinates). \throw UsageError for a malformed one.
    std::vector<FocusRegion> parsed_focus() const
    {
        std::vector<FocusRegion> regions;
        for (const std::string& spec : focus) {
            const std::size_t colon = spec.find(':');
            const auto v = parse_numbers(spec.substr(0, colon), ',', "--focus");
            if (v.size() != 4 || v[3] < 0)
                throw UsageError("--focus: expected X,Y,Z,R[:TOL] with R >= 0, got '" + spec + "'");
            FocusRegion r;
            r.centre = Vec3{v[0], v[1], v[2]};
            r.radius = v[3];
            if (colon != std::string::npos) {
                const auto t = parse_numbers(spec.substr(colon + 1), ',', "--focus tolerance");
                if (t.size() != 1 || t[0] < 0)
                    throw UsageError("--focus: the tolerance after ':' must be one number >= 0, got '" + spec + "'");
                r.tolerance = t[0];
            }
            regions.push_back(r);
        }
        return regions;
    }

    // Everything that can be checked without the model, before any work.
    void validate() const
    {
        if (!camera.empty())
            parsed_camera();
        parsed_focus();
    }

    // The cut's tolerance relative to the model's scale (Hierarchy::scale, what cut_by_tolerance takes).
    double base_tolerance(const Hierarchy& h) const
    {
        if (error >= 0)
            return h.scale > 0 ? error / h.scale : 0.0;
        return tolerance >= 0 ? tolerance : kDefaultTolerance;
    }

    // Whether some point of the model lies in the focus sphere (one lying inside the model's box can
    // still hold none: the hollow of a scanned vessel; QA round 28 found it refined without a word).
    static bool holds_a_point(const Hierarchy& h, const FocusRegion& r)
    {
        const Vec3 reach{r.radius, r.radius, r.radius};
        for (const std::uint32_t i : points_in_box(h, BoundingBox{r.centre - reach, r.centre + reach}))
            if (distance(h.cloud.positions[i], r.centre) <= r.radius)
                return true;
        return false;
    }

    // The camera of --camera in the model's frame, its pixel error made finer by `step` as cut() does.
    Camera camera_at(const Hierarchy& h, int step) const
    {
        Camera cam = parsed_camera();
        cam.position = cam.position - h.cloud.origin;
        cam.max_pixel_error *= std::pow(0.5, 0.5 * step);
        return cam;
    }

    // The --focus regions in the model's frame, their tolerances made finer by `step` as cut() does.
    std::vector<FocusRegion> regions_at(const Hierarchy& h, int step) const
    {
        std::vector<FocusRegion> regions = parsed_focus();
        for (FocusRegion& region : regions) {
            region.centre = region.centre - h.cloud.origin;
            region.tolerance *= std::pow(0.5, 0.5 * step);
        }
        return regions;
    }

    // The cut asked (step 0), or for mesh_mended a finer one that still meets every bound asked: each
    // tolerance and the camera's pixel error / √2^step, τ / 2^step. A tile budget is a count, not a
    // bound: it is not made finer.
    Cut cut(const Hierarchy& h, int step = 0) const
    {
        const double finer = std::pow(0.5, 0.5 * step);
        const Vec3 origin = h.cloud.origin;
        if (!camera.empty())
            return cut_for_camera(h, camera_at(h, step));
        if (tiles > 0)
            return cut_by_budget(h, tiles);
        if (tau > 0)
            return cut_by_tau(h, tau * finer * finer);
        if (focus.empty())
            return cut_by_tolerance(h, base_tolerance(h) * finer);
        const std::vector<FocusRegion> regions = regions_at(h, step);
        for (std::size_t k = 0; k < regions.size() && step == 0; ++k) {
            // Coordinates in another frame (local ones for a georeferenced model, say) miss the model.
            if (!intersects(h.nodes.front(), regions[k]))
                std::printf("note: --focus %s: the sphere does not meet the model's points (bounding box %.9g,%.9g,%.9g "
                            "to %.9g,%.9g,%.9g); it refines nothing\n",
                            focus[k].c_str(), h.nodes.front().box.min.x + origin.x, h.nodes.front().box.min.y + origin.y,
                            h.nodes.front().box.min.z + origin.z, h.nodes.front().box.max.x + origin.x,
                            h.nodes.front().box.max.y + origin.y, h.nodes.front().box.max.z + origin.z);
            else if (!holds_a_point(h, regions[k]))
                std::printf("note: --focus %s: no point of the model lies in the sphere; it refines only the tiles "
                            "whose bounding boxes reach into it\n",
                            focus[k].c_str());
        }
        return cut_by_regions(h, base_tolerance(h) * finer, regions);
    }
};

struct MeshArgs
{
    double alpha = 0.0;
    std::string height_field = "auto";
    bool keep_steps = false;
    std::string stats_json;
    bool no_quality = false;
    double refine_fans = 0.0;
    int fit_rounds = FitOptions{}.rounds;
    bool no_colors = false;
    std::size_t close_holes = 0;
    int crack_rounds = MeshOptions{}.crack_rounds;
    int crossing_rounds = MeshOptions{}.crossing_rounds;
    int hole_rounds = MeshOptions{}.hole_rounds;
    bool thin_walls = false;
    const CLI::Option* crack_option = nullptr;    // one mesh only: LOD levels are mended by whole cuts
    const CLI::Option* crossing_option = nullptr;
    const CLI::Option* hole_option = nullptr;

    //! `one_mesh` false: `lods`, whose per-level statistics go to lods.json (no --stats-json).
    void add(CLI::App* cmd, bool one_mesh = true)
    {
        cmd->add_option("--alpha", alpha, "gap triangulation alpha in model units (default: automatic)")
            ->check(kPositive);
        cmd->add_option("--height-field", height_field, "2D Delaunay on the projection: auto, on or off")
            ->check(CLI::IsMember({"auto", "on", "off"}))
            ->capture_default_str();
        cmd->add_flag("--keep-steps", keep_steps, "height fields: keep step discontinuities open (paper Fig. 9b)");
        if (one_mesh)
            cmd->add_option("--stats-json", stats_json, "write the mesh statistics as JSON to this file")->check(kNonEmpty);
        cmd->add_flag("--no-quality", no_quality,
                      one_mesh ? "skip the point-to-mesh distance measurement"
                               : "refused here: lods measures every level (a finer level measured worse than the one kept before it is left out)");
        cmd->add_option("--refine-fans", refine_fans,
                        "insert fan points deviating more than F x their tile's RMS plane distance (0 = off; try 1-2)")
            ->check(kNonNegative);
        cmd->add_option("--fit-rounds", fit_rounds,
                        "least-squares rounds fitting the vertices to the points (0 = interpolate, as the paper)")
            ->check(integer_check(0, kMaxFitRounds))
            ->capture_default_str();
        cmd->add_flag("--no-colors", no_colors, "leave the mesh uncoloured even when the points have colours");
        cmd->add_flag("--thin-walls", thin_walls,
                      "tell the two sides of walls about 3 point spacings thick and more apart (a shell, a plate sampled on "
                      "both sides); may open the rims of plates whose rims are not sampled (README: Choices, thin walls)");
        cmd->add_option("--close-holes", close_holes,
                        "also fill the sample's own holes of at most N edges, for watertight output (0 = off; at most 2000)")
            ->check(integer_check(0, 2000));
        // LOD levels are mended by whole tolerance cuts instead (lod_set.h), so that they nest.
        if (one_mesh)
            crack_option = cmd->add_option("--crack-rounds", crack_rounds,
                                           "rounds refining the tiles along cracks of a closed surface and meshing again (0 = off)")
                               ->check(integer_check(0, kMaxRefineRounds))
                               ->capture_default_str();
        if (one_mesh)
            crossing_option = cmd->add_option("--crossing-rounds", crossing_rounds,
                                              "rounds refining the tiles of faces that cross each other and meshing again (0 = off)")
                                  ->check(integer_check(0, kMaxRefineRounds))
                                  ->capture_default_str();
        if (one_mesh)
            hole_option = cmd->add_option("--hole-rounds", hole_rounds,
                                          "rounds refining the tiles of faces over holes of the sample and meshing again (0 = off)")
                              ->check(integer_check(0, kMaxRefineRounds))
                              ->capture_default_str();
    }

    MeshOptions options() const
    {
        MeshOptions o;
        o.surface.alpha = alpha;
        o.surface.height_field = height_field == "on" ? HeightField::On : height_field == "off" ? HeightField::Off : HeightField::Auto;
        o.surface.bridge_steps = !keep_steps;
        o.refine.max_deviation = refine_fans;
        o.fit.rounds = fit_rounds;
        o.colors.enabled = !no_colors;
        o.surface.close_holes = close_holes;
        o.crack_rounds = crack_rounds;
        o.crossing_rounds = crossing_rounds;
        o.hole_rounds = hole_rounds;
        o.tiles.meet_factor = thin_walls ? kThinWallMeetFactor : 0.0;
        return o;
    }
};

struct OutputArgs
{
    bool draco = false;
    int quantize = 14;
    std::string up = "z";
    CLI::Option* quantize_option = nullptr;

    // --quantize acts on Draco only: without --draco it would be ignored, except in a .drc file.
    // --draco and --up y act on glTF/GLB and 3D Tiles content only (and --draco is what a .drc is):
    // on another format they would be ignored. `written` is what is written: the output's extension,
    // "3dtiles", or the mesh format of lods' files.
    void validate(const fs::path& out, const std::string& written = "") const
    {
        const std::string kind = written.empty() ? lower_extension(out) : written;
        if (given(quantize_option) && !draco && kind != ".drc")
            throw UsageError("--quantize: sets Draco's quantization; add --draco (or write a .drc file)");
        const bool gltf = kind == ".glb" || kind == ".gltf" || kind == "3dtiles";
        if (draco && !gltf && kind != ".drc")
            throw UsageError("--draco: compresses glTF/GLB and 3D Tiles content; a " + kind + " file has no Draco");
        if (up == "y" && !gltf)
            throw UsageError("--up y: turns the input into glTF's y-up frame; a " + kind +
                             " file keeps the input's axes, so it would have no effect");
    }

    void add(CLI::App* cmd)
    {
        cmd->add_flag("--draco", draco, "Draco-compress glTF/GLB and 3D Tiles content");
        quantize_option = cmd->add_option("--quantize", quantize, "Draco position quantization bits (with --draco or .drc)")
                              ->check(integer_check(1, kMaxPositionBits))
                              ->capture_default_str();
        cmd->add_option("--up", up, "up axis of the input (glTF is y-up): z or y")->check(CLI::IsMember({"z", "y"}))->capture_default_str();
    }

    GltfOptions gltf() const
    {
        GltfOptions o;
        o.draco = draco;
        o.draco_options.position_bits = quantize;
        o.up_axis = up == "y" ? UpAxis::Y : UpAxis::Z;
        return o;
    }
};

const char* const kMeshExtensionHelp =
    "unknown output extension (use .ply .obj .off .stl .om .glb .gltf .drc; export and reconstruct also take a directory with --format 3dtiles)";

bool is_mesh_extension(const std::string& ext)
{
    for (const char* known : {".glb", ".gltf", ".drc", ".ply", ".obj", ".off", ".stl", ".om"})
        if (ext == known)
            return true;
    return false;
}

// Draco snaps positions to a grid of 2^bits - 1 steps across the mesh's largest side. Where a step
// is a sizeable part of an edge, vertices merge and faces collapse in the decoded mesh, which the
// printed statistics (of the mesh before quantization) do not show: `--quantize 1` kept 8 of the
// bunny's 5,741 positions without a word (QA, session 20). Say so.
// The sides of the mesh's bounding box (0 without vertices).
Mesh::Point mesh_extent(const Mesh& mesh)
{
    if (mesh.n_vertices() == 0)
        return {0, 0, 0};
    Mesh::Point lo = mesh.point(*mesh.vertices_begin()), hi = lo;
    for (const auto v : mesh.vertices()) {
        lo.minimize(mesh.point(v));
        hi.maximize(mesh.point(v));
    }
    return hi - lo;
}

// `range`: the extent the bits divide (0: the mesh's own, as one mesh's Draco grid); `chosen`: the
// bits were picked by the tileset, not by --quantize (QA round 57: the note blamed a --quantize 24 the
// user never gave, and suggested the 14-bit default, coarser still).
void note_coarse_quantization(const Mesh& mesh, int bits, const fs::path& out, double range = 0.0, bool chosen = false)
{
    if (mesh.n_edges() == 0)
        return;
    const double mean_edge = mean_edge_length(mesh);
    const double step = (range > 0.0 ? range : mesh_extent(mesh).max()) / (std::ldexp(1.0, bits) - 1.0);
    if (!(step > 0.25 * mean_edge))
        return;
    if (chosen)
        std::printf("note: %s: Draco positions at %d bits, the most Draco takes, snap to steps of %.3g on the tileset's "
                    "%.3g-wide grid, %.0f%% of the finest level's mean edge length: vertices merge and faces collapse "
                    "when decoded (the statistics are of the mesh before quantization); leave --draco out, or export "
                    "parts far apart separately\n",
                    out.string().c_str(), bits, step, range, 100.0 * step / mean_edge);
    else
        std::printf("note: %s: --quantize %d snaps positions to steps of %.3g, %.0f%% of the mean edge length: "
                    "vertices merge and faces collapse when decoded (the statistics are of the mesh before "
                    "quantization); more bits keep them apart\n",
                    out.string().c_str(), bits, step, 100.0 * step / mean_edge);
}

// Writes a mesh to any supported single-file format, chosen by extension. Notes name `shown` (the path
// the user will find the file at, when `out` is inside a directory built aside), else `out`.
void write_any_mesh(const Mesh& mesh, const Vec3& origin, const fs::path& out, const OutputArgs& args,
                    const fs::path& shown = {})
{
    const std::string ext = lower_extension(out);
    const fs::path& named = shown.empty() ? out : shown;
    if (ext == ".glb" || ext == ".gltf") {
        write_gltf(mesh, origin, out, args.gltf());
        if (args.draco)
            note_coarse_quantization(mesh, args.quantize, named);
    } else if (ext == ".drc") {
        DracoOptions d;
        d.position_bits = args.quantize;
        write_drc(mesh, origin, out, d);
        note_coarse_quantization(mesh, args.quantize, named);
        // Draco has no transform, and float positions far from 0 lose their digits: the file keeps
        // them relative to the origin, which a reader must add back. Say so where it matters.
        if (origin != Vec3{0, 0, 0})
            std::printf("note: %s: positions are relative to the model's origin (%s), stored as its "
                        "\"mrtile_origin\" metadata entry (Draco has no transform)\n",
                        named.string().c_str(), shortest(origin, ", ").c_str());
    } else if (is_mesh_extension(ext)) { // OpenMesh's writers: .ply .obj .off .stl .om
        write_mesh(mesh, origin, out);
        if (ext == ".stl" && stl_is_relative(mesh, origin))
            std::printf("note: %s: positions are relative to the model's origin (%s): STL has only 32-bit "
                        "floats, which lose digits that far out (.ply, .obj and .off keep absolute double coordinates)\n",
                        named.string().c_str(), shortest(origin, ", ").c_str());
    } else {
        throw UsageError(out.string() + ": " + kMeshExtensionHelp);
    }
}

// Where the noise floor stops a cut of points the build did not denoise (noise too little or too
// local for the automatic rule), the other remedy.
const char* denoise_hint(const Hierarchy& h)
{
    return h.info.denoised ? "" : "; or build with --denoise on to move the points onto the surface first";
}

// What the noise-floor notes and `info` call the points: "noisy" (the notes add the denoising hint)
// only when the sample is (sample_is_noisy) or was denoised; otherwise a few rough leaves, as at the
// sharp edges of a clean CAD part (fandisk: 1 of 463 tiles), which denoising would round off.
bool noisy_as_a_whole(const Hierarchy& h) { return h.info.denoised || sample_is_noisy(h); }
const char* noise_words(bool noisy)
{
    return noisy ? "the points are noisy" : "some points are rough (sharp edges, local noise or overlapping scans)";
}

std::string noise_note(const Hierarchy& h, const std::string& what)
{
    const bool noisy = noisy_as_a_whole(h);
    return std::string("note: ") + noise_words(noisy) + ": " + what + "; --below-noise goes on" + (noisy ? denoise_hint(h) : "");
}

nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

nlohmann::json mesh_json(const MeshResult& r, const QualityReport* q, double seconds)
{
    nlohmann::json j;
    j["tiles"] = r.tiles;
    j["vertices"] = r.mesh.n_vertices();
    j["faces"] = r.mesh.n_faces();
    j["fan_faces"] = r.surface.fan_faces;
    j["gap_faces"] = r.surface.gap_faces;
    j["refused_faces"] = r.surface.refused_faces;
    j["holes_filled"] = r.surface.holes_filled;
    j["closings_refused"] = r.surface.closings_refused;
    j["refined_points"] = r.refined_points;
    j["notches"] = r.notches;
    j["covered_holes_closed"] = r.covered_holes.closed;
    j["bridges_cut"] = r.bridges.tubes;
    j["fit_rounds"] = r.fit.rounds;
    j["fit_clamped"] = r.fit.clamped;
    j["fit_flips"] = r.fit.flips;
    j["fit_reverted"] = r.fit.reverted;
    j["sliver_flips"] = r.slivers.flips;
    j["untangled_pairs"] = r.untangle.pairs_before - r.untangle.pairs_after;
    j["relaxed_moves"] = r.fit.relax.moves;
    j["height_field"] = r.surface.height_field_used;
    j["alpha"] = r.surface.alpha;
    // With a viewpoint: whether the cloud is one view from it (no handles made), and why not.
    j["single_view"] = r.surface.view ? nlohmann::json(r.surface.view->single_view) : nlohmann::json(nullptr);
    j["hidden_share"] = r.surface.view ? nlohmann::json(r.surface.view->hidden_share) : nlohmann::json(nullptr);
    if (q) {
        j["boundary_loops"] = q->topology.boundary_loops;
        j["genus"] = q->topology.genus;
        j["components"] = q->topology.components;
        j["nonmanifold_edges"] = q->topology.nonmanifold_edges;
        j["nonmanifold_vertices"] = q->topology.nonmanifold_vertices;
        j["consistently_oriented"] = q->topology.consistently_oriented;
        j["e_rms"] = q->e_rms;
        j["self_intersections"] = q->self_intersections;
        j["caps"] = q->caps;
        j["mean_distance"] = q->point_to_mesh.mean;
        j["max_distance"] = q->point_to_mesh.max;
        j["median_distance"] = q->point_to_mesh.median;
        j["p99_distance"] = q->point_to_mesh.p99;
        j["mesh_to_points_mean"] = q->mesh_to_points.mean;
        j["mesh_to_points_max"] = q->mesh_to_points.max;
        j["far_points"] = q->point_to_mesh.far;
        j["line_points"] = q->line_points;
        j["sharp_loops"] = q->sharp_loops;
        j["points"] = q->points;
        j["diagonal"] = q->point_to_mesh.diagonal; // model units: what the distance fractions are of
        j["mesh_diagonal"] = mesh_extent(r.mesh).norm();
    } else {
        // --no-quality skips the distances (null), not the topology, which is cheap and documented.
        const TopologyStats t = topology_stats(r.mesh);
        j["boundary_loops"] = t.boundary_loops;
        j["genus"] = t.genus;
        j["components"] = t.components;
        j["nonmanifold_edges"] = t.nonmanifold_edges;
        j["nonmanifold_vertices"] = t.nonmanifold_vertices;
        j["consistently_oriented"] = t.consistently_oriented;
        j["caps"] = count_caps(r.mesh); // cheap, like the topology
        for (const char* key : {"e_rms", "mean_distance", "max_distance", "median_distance", "p99_distance",
                                "mesh_to_points_mean", "mesh_to_points_max", "self_intersections", "far_points", "line_points", "sharp_loops", "points", "diagonal",
                                "mesh_diagonal"})
            j[key] = nullptr;
    }
    j["seconds"] = seconds;
    return j;
}

void print_mesh_report(const nlohmann::json& j, const fs::path& out)
{
    std::printf("wrote %s: %s, %zu vertices, %zu faces", out.string().c_str(), count_of(j["tiles"].get<std::size_t>(), "tile", "tiles").c_str(),
                j["vertices"].get<std::size_t>(), j["faces"].get<std::size_t>());
    if (j.contains("genus") && j["e_rms"].is_null())
        std::printf(", %s, genus %d, %zu non-manifold edges, %zu non-manifold vertices",
                    count_of(j["boundary_loops"].get<std::size_t>(), "boundary loop", "boundary loops").c_str(), j["genus"].get<int>(), j["nonmanifold_edges"].get<std::size_t>(),
                    j["nonmanifold_vertices"].get<std::size_t>());
    else if (j.contains("genus"))
        std::printf(", %s, genus %d, %zu non-manifold edges, %zu non-manifold vertices, E_RMS %.3g, "
                    "mean/max distance %.3g/%.3g of the diagonal (mesh to points: max %.3g)",
                    count_of(j["boundary_loops"].get<std::size_t>(), "boundary loop", "boundary loops").c_str(), j["genus"].get<int>(), j["nonmanifold_edges"].get<std::size_t>(),
                    j["nonmanifold_vertices"].get<std::size_t>(), j["e_rms"].get<double>(), j["mean_distance"].get<double>(),
                    j["max_distance"].get<double>(), j["mesh_to_points_max"].get<double>());
    if (j.contains("genus") && !j["e_rms"].is_null() && j.value("distances_to", "") == "denoised points")
        std::printf(" (to the denoised points)");
    std::printf(" (%.2f s)\n", j["seconds"].get<double>());
    // Points the mesh leaves out, far from it, set the maximum and widen the diagonal the fractions
    // are of (a 50-point blob 5,000 radii from a sphere: left out without a word, and every fraction
    // 2,500 times smaller than the sphere's own; QA, session 20).
    // Inside the mesh's own extent they are sampled surface the mesh leaves out, not strays (QA round 5).
    if (j.contains("far_points") && j["far_points"].is_number() && j["far_points"].get<std::size_t>() > 0) {
        const double diagonal = j.value("diagonal", 0.0);
        // Counted after duplicates are merged (QA round 50: 5,000 "no return" points at the origin were
        // "1 input points"): one point, one verb.
        const std::size_t far = j["far_points"].get<std::size_t>();
        const char* lie = far == 1 ? "point lies" : "points lie";
        if (j.value("mesh_diagonal", 0.0) < 0.9 * diagonal)
            std::printf("note: %zu distinct input %s far from the mesh (beyond %.0f%% of the diagonal and twice the coarsest "
                        "tile's error): pieces too small to mesh or strays, left out (--remove-outliers drops strays); "
                        "they widen the diagonal (%.6g) that the fractions above are of\n",
                        far, lie, 100.0 * kFarFraction, diagonal);
        else
            std::printf("note: %zu distinct input %s far from the mesh (beyond %.0f%% of the diagonal and twice the coarsest "
                        "tile's error), within its extent: sampled surface the mesh leaves out (a hole over sparse "
                        "points, or a piece too small to mesh), or strays inside it (--remove-outliers drops strays)\n",
                        far, lie, 100.0 * kFarFraction);
    }
    // Crossing faces were counted in the stats only (QA round 43: 207 pairs on a sampled fandisk, on
    // the console not a word).
    if (j.contains("self_intersections") && j["self_intersections"].is_number() && j["self_intersections"].get<std::size_t>() > 0)
        std::printf("note: %s of faces cross each other, left after untangling (a fold at a thin tip or a sharp "
                    "edge, or overlapping scans that disagree; README: Known limits)\n",
                    count_of(j["self_intersections"].get<std::size_t>(), "pair", "pairs").c_str());
    // Points along a curve (a helix of 20,000 points made 49 ribbons without a word; QA round 6).
    if (j.contains("line_points") && j["line_points"].is_number() && j["points"].is_number()) {
        const auto lines = j["line_points"].get<std::size_t>(), points = j["points"].get<std::size_t>();
        if (points > 0 && lines * 10 >= points)
            std::printf("note: %.0f%% of the points lie in tiles that are lines, not patches (under %.0f%% as wide as "
                        "long): the input follows curves there (a wire, single scan lines), and the mesh is ribbons "
                        "along them\n",
                        100.0 * static_cast<double>(lines) / static_cast<double>(points), 100.0 * kLineWidthRatio);
    }
    // Loops along acute edges (QA round 8: every closed solid with an edge of 70 degrees or less was
    // left open there, and nothing but the loop count said so).
    if (j.contains("sharp_loops") && j["sharp_loops"].is_number() && j["sharp_loops"].get<std::size_t>() > 0)
        std::printf("note: %zu of the %zu boundary loops run along sharp edges of the mesh (its faces on their two "
                    "sides turn more than %.0f degrees): a closed solid's edges of about 70 degrees or less are often "
                    "left open (README: Known limits), and another tolerance may close them; in a scan such a loop "
                    "can also be where the scanned surface simply ends, and is right\n",
                    j["sharp_loops"].get<std::size_t>(), j["boundary_loops"].get<std::size_t>(), kSharpLoopDegrees);
}

// A further file for the same mesh (the demo writes its mesh as .ply and as Draco .glb).
struct AlsoWrite
{
    fs::path path;
    OutputArgs args;
};

// Measure + write a cut's mesh: the second half of mesh_and_write.
nlohmann::json write_meshed(const Hierarchy& h, const MeshResult& r, const MeshArgs& mesh_args, const OutputArgs& out_args,
                            const fs::path& out, const std::vector<AlsoWrite>& also, Clock::time_point start)
{
    QualityReport q;
    if (!mesh_args.no_quality)
        q = measure_quality(h, r.cut, r.mesh);
    // All or none: a disk full on the statistics or a further file left the mesh written (QA round 66).
    CommitTogether outputs;
    write_any_mesh(r.mesh, h.cloud.origin, out, out_args);
    nlohmann::json j = mesh_json(r, mesh_args.no_quality ? nullptr : &q, seconds_since(start));
    // A denoised model loaded has only its moved points to measure against (measure_quality).
    j["denoised"] = h.info.denoised;
    j["distances_to"] = h.info.denoised && h.raw_positions.empty() ? "denoised points" : "input points";
    if (!mesh_args.stats_json.empty())
        write_file_atomically(mesh_args.stats_json, j.dump(2) + "\n");
    std::vector<double> also_seconds;
    for (const AlsoWrite& a : also) {
        const auto again = Clock::now();
        write_any_mesh(r.mesh, h.cloud.origin, a.path, a.args);
        also_seconds.push_back(seconds_since(again));
    }
    outputs.commit();
    print_mesh_report(j, out);
    // Which loops --close-holes left, and why: the counts must add up to the loops printed (a closed
    // object broken into pieces kept 3 loops, and the note named 2 of them as a view's outline; QA,
    // session 20).
    if (mesh_args.close_holes > 0 && j["boundary_loops"].is_number()) {
        const auto loops = j["boundary_loops"].get<std::size_t>();
        const std::size_t refused = std::min(loops, r.surface.closings_refused);
        if (loops > 0)
            std::printf("note: --close-holes %zu: %zu boundary loops left open: %zu whose cap would cut through the "
                        "surface (the outline of a single view, or a crack between pieces), %zu longer than %zu edges "
                        "or not closable by a manifold cap\n",
                        mesh_args.close_holes, loops, refused, loops - refused, mesh_args.close_holes);
    }
    for (std::size_t k = 0; k < also.size(); ++k)
        std::printf("wrote %s: the same mesh (%.2f s)\n", also[k].path.string().c_str(), also_seconds[k]);
    return j;
}

// A mesh of points that look airborne (SurfaceStats::looks_airborne), meshed in 3D for want of a CRS:
// when it is in pieces, name the two ways to a height field.
void note_airborne(const Mesh& mesh)
{
    if (topology_stats(mesh).components > 1)
        std::printf("note: the points look like an airborne scan (ground and roofs facing up z), meshed in 3D for want "
                    "of a coordinate system; --height-field on (or a CRS: build or reconstruct with --crs, which a LAS "
                    "file usually carries) meshes them as a height field, its walls bridged\n");
}

// The same for a LOD set, once, by its finest level that looks so.
void note_airborne(const LodSet& set)
{
    for (auto level = set.levels.rbegin(); level != set.levels.rend(); ++level)
        if (level->looks_airborne) {
            note_airborne(level->mesh);
            return;
        }
}

// Closed pieces whose bounding boxes meet: objects side by side or nested, or one thin part broken at
// cracks and capped there (QA round 50: a pipe 4-6 point spacings across came out as 10 closed segments
// end to end, said nowhere; mesh_mended's in-pieces check looks at pieces with open borders only).
void note_touching_closed_pieces(const Mesh& mesh)
{
    UnionFind pieces(mesh.n_vertices());
    for (const auto e : mesh.edges())
        pieces.unite(static_cast<std::uint32_t>(mesh.from_vertex_handle(mesh.halfedge_handle(e, 0)).idx()),
                     static_cast<std::uint32_t>(mesh.to_vertex_handle(mesh.halfedge_handle(e, 0)).idx()));
    struct Piece
    {
        BoundingBox box;
        bool open = false, seen = false;
    };
    std::vector<Piece> by_root(mesh.n_vertices());
    for (const auto v : mesh.vertices()) {
        if (mesh.is_isolated(v))
            continue;
        Piece& piece = by_root[pieces.find(static_cast<std::uint32_t>(v.idx()))];
        const Vec3 p = to_vec3(mesh.point(v));
        piece.box = piece.seen ? BoundingBox{min(piece.box.min, p), max(piece.box.max, p)} : BoundingBox{p, p};
        piece.seen = true;
        piece.open = piece.open || mesh.is_boundary(v);
    }
    std::vector<BoundingBox> closed;
    for (const Piece& piece : by_root)
        if (piece.seen && !piece.open)
            closed.push_back(piece.box);
    if (closed.size() < 2)
        return;
    // Sort and sweep along x: each pair whose x ranges overlap is tested once.
    std::sort(closed.begin(), closed.end(), [](const BoundingBox& a, const BoundingBox& b) { return a.min.x < b.min.x; });
    std::vector<char> meets(closed.size(), 0);
    for (std::size_t i = 0; i < closed.size(); ++i)
        for (std::size_t k = i + 1; k < closed.size() && closed[k].min.x <= closed[i].max.x; ++k)
            if (closed[i].meets(closed[k]))
                meets[i] = meets[k] = 1;
    const auto touching = static_cast<std::size_t>(std::count(meets.begin(), meets.end(), 1));
    if (touching > 0)
        std::printf("note: the mesh has %zu closed pieces, %zu of them within another's bounding box or touching it: "
                    "objects side by side or nested, or a thin part (a pipe or wall a few point spacings across) "
                    "broken and capped where it broke (README: Known limits)\n",
                    closed.size(), touching);
}

void check_up_axis(const Hierarchy& h, const OutputArgs& o); // below, with the CRS helpers

// Cut + mesh + measure + write: shared by `mesh`, `reconstruct` and `demo`. The mesh is used where it
// was made: an OpenMesh mesh has no move constructor, so moving a MeshResult into a variable declared
// earlier would copy it.
nlohmann::json mesh_and_write(const Hierarchy& h, const CutArgs& cut_args, const MeshArgs& mesh_args,
                              const OutputArgs& out_args, const fs::path& out, const std::vector<AlsoWrite>& also = {})
{
    const auto start = Clock::now();
    check_up_axis(h, out_args);
    if (cut_args.triangles > 0) {
        const TriangleCountResult t = mesh_to_triangle_count(h, cut_args.triangles, mesh_args.options());
        if (t.result.mesh.n_faces() > cut_args.triangles)
            std::printf("note: no cut meshes to %zu triangles or fewer; this is the coarsest one found\n",
                        cut_args.triangles);
        if (t.smaller_budget)
            std::printf("note: the largest tile budget that fits meshed in %zu pieces that the sample joins; meshed a "
                        "budget of %zu tiles instead%s\n",
                        t.asked.components, t.cut.size(), t.in_pieces ? "; still in pieces there" : "");
        else if (t.in_pieces)
            std::printf("note: the mesh is in %zu pieces that the sample joins; no smaller budget tried joined them\n",
                        t.asked.components);
        return write_meshed(h, t.result, mesh_args, out_args, out, also, start);
    }
    // A cut in pieces that the sample joins is meshed finer (mesh_mended): a finer cut meets the
    // bounds asked too. A tile budget is meshed as it is.
    const bool plain = cut_args.tiles == 0 && cut_args.tau == 0 && cut_args.camera.empty() && cut_args.focus.empty();
    const MendedMeshResult mended = mesh_mended(h, [&](int step) { return cut_args.cut(h, step); }, mesh_args.options(),
                                                cut_args.tiles > 0 ? 0 : 3);
    if (mended.steps > 0) {
        const double finer = std::pow(0.5, 0.5 * mended.steps);
        char what[96];
        if (!cut_args.camera.empty())
            std::snprintf(what, sizeof what, "at a pixel error of %.4g", cut_args.parsed_camera().max_pixel_error * finer);
        else if (cut_args.tau > 0)
            std::snprintf(what, sizeof what, "at tau %.4g", cut_args.tau * finer * finer);
        else
            std::snprintf(what, sizeof what, "at tolerance %.4g%s", cut_args.base_tolerance(h) * finer,
                          cut_args.focus.empty() ? "" : " (and each --focus tolerance as much finer)");
        std::printf("note: the cut meshed in %zu pieces that the sample joins; meshed %s instead (a finer cut, it meets "
                    "what was asked too)%s\n",
                    mended.asked.components, what, mended.in_pieces ? "; still in pieces there" : "");
    }
    if (mended.thin_walls)
        std::printf("note: the mesh was in pieces that the sample joins; meshed with --thin-walls instead (the two sides "
                    "of a wall a few point spacings thick, joined and torn apart: README, Choices, thin walls)%s\n",
                    mended.in_pieces ? "; still in pieces" : "");
    const MeshResult& r = mended.result;
    if (mended.in_pieces && mended.steps == 0 && !mended.thin_walls)
        std::printf("note: the mesh is in %zu pieces that the sample joins; %s\n", mended.asked.components,
                    cut_args.tiles > 0 ? "a larger --tiles budget may join them (bounds, such as --tolerance, are meshed "
                                         "finer where so)"
                                       : "no finer cut tried joined them");
    if (r.surface.looks_airborne)
        note_airborne(r.mesh);
    note_touching_closed_pieces(r.mesh);
    if (r.surface.view && !r.surface.view->single_view && h.cloud.viewpoint) {
        const Vec3 v = *h.cloud.viewpoint + h.cloud.origin;
        std::printf("note: the points are not clearly one view from the viewpoint (%.6g, %.6g, %.6g): %.2g%% of them "
                    "lie behind others from there (several views merged, or a noisy view?), so handles are allowed as "
                    "without a viewpoint (README: Choices, single views)\n",
                    v.x, v.y, v.z, 100.0 * r.surface.view->hidden_share);
    }
    // Tiles of a tolerance, region or camera cut that only their noise floor kept from refining: of
    // the cut as made, not as mesh_cut refined it (refined children can be rougher than their parent's
    // bound). A region or camera cut is made again here (without the region notes of its first making).
    const double finer = std::pow(0.5, 0.5 * mended.steps);
    const bool by_camera = !cut_args.camera.empty(), by_region = !cut_args.focus.empty();
    const bool floored = max_noise_floor(h) > 0;
    const Camera camera = by_camera ? cut_args.camera_at(h, mended.steps) : Camera{};
    const std::vector<FocusRegion> regions = by_region ? cut_args.regions_at(h, mended.steps) : std::vector<FocusRegion>{};
    Cut cut;
    if (plain)
        cut = cut_args.cut(h, mended.steps);
    else if (by_camera && floored)
        cut = cut_for_camera(h, camera);
    else if (by_region && floored)
        cut = cut_by_regions(h, cut_args.base_tolerance(h) * finer, regions);
    const auto asks_finer = [&](const Node& n) {
        if (by_camera)
            return camera_asks_finer(n, camera);
        return n.rms_plane_distance > region_tolerance(n, cut_args.base_tolerance(h) * finer, regions) * h.scale;
    };
    std::size_t stopped = 0;
    for (std::int32_t id : cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        // A tile kept whole over single scan lines is no noise (splits_into_lines, cut.h).
        stopped += !n.is_leaf() && asks_finer(n) && n.rms_plane_distance <= n.noise_floor && !splits_into_lines(h, n) ? 1 : 0;
    }
    if (stopped > 0) {
        char what[160];
        // "of the cut's N": the mesh's own count, which refinement around small pieces can raise, is
        // printed next (QA round 77 read "220 of 4263 tiles" against "4267 tiles").
        std::snprintf(what, sizeof what, "%zu of the cut's %zu tiles stop at their noise floor (up to %.3g of the size)", stopped,
                      cut.size(), max_noise_floor(h) / h.scale);
        std::printf("%s\n", noise_note(h, what).c_str());
    }
    return write_meshed(h, r, mesh_args, out_args, out, also, start);
}

struct ExportArgs
{
    std::string format;
    std::size_t max_tile_triangles = LodSetOptions{}.max_tile_triangles;
    std::string tolerance_list; // --lod-tolerances as given (checked by kNonNegativeList)
    std::size_t levels = 0;
    std::string enu;
    double geoid_height = 0.0;

    //! `lods_command`: the `lods` command, which writes mesh files only (no 3D Tiles placement).
    void add(CLI::App* cmd, bool lods_command = false)
    {
        if (lods_command) {
            cmd->add_option("--format", format, "the level files' format (default ply)")
                ->check(CLI::IsMember({"glb", "gltf", "drc", "ply", "obj", "off", "stl", "om"}));
        } else {
            cmd->add_option("--format", format,
                            "3dtiles (a directory), lod-glb (one .glb with every level, MSFT_lod), or by the output's extension")
                ->check(CLI::IsMember({"3dtiles", "lod-glb", "glb", "gltf", "drc", "ply", "obj", "off", "stl", "om"}));
            enu_option = cmd->add_option("--enu", enu,
                                         "3D Tiles: the model is in local east-north-up metres at LON,LAT,HEIGHT (WGS84); "
                                         "the root transform maps it to ECEF")
                             ->check(kNonEmpty);
            geoid_option = cmd->add_option("--geoid-height", geoid_height,
                                           "3D Tiles placed by the model's CRS: metres added to every height (the geoid's "
                                           "height above the ellipsoid, for orthometric heights; |M| <= 10000)")
                               ->check(kNonEmpty); // '' read as 0 (QA round 34)
        }
        lod_options.push_back(cmd->add_option("--max-tile-triangles", max_tile_triangles,
                                              lods_command ? "level 0's budget: three quarters of min(this, 4096) "
                                                             "triangles (at most 3072)"
                                                           : "largest number of triangles in one 3D Tiles tile")
                                  ->check(integer_check(64, 1ull << 31))
                                  ->capture_default_str());
        auto* l = cmd->add_option("--levels", levels,
                                  lods_command ? "number of levels of detail: level 0 (the best cut of at most three quarters "
                                                 "of --max-tile-triangles or of 4096, whichever is fewer), then the tolerance halved per level "
                                                 "(default: down to the hierarchy's leaves)"
                                               : "number of levels of detail: level 0 (the best cut whose mesh fits one tile, "
                                                 "three quarters of --max-tile-triangles), then the tolerance halved per level; "
                                                 "the tiles refine down to the last (default: down to the hierarchy's leaves)")
                      ->check(integer_check(1, kMaxLevels));
        auto* t = cmd->add_option("--lod-tolerances", tolerance_list, "explicit level tolerances, coarse to fine")
                      ->check(kNonNegativeList);
        l->excludes(t);
        lod_options.push_back(l);
        lod_options.push_back(t);
    }

    static constexpr unsigned long long kMaxLevels = 32; // a level halves the error: 2^-32 is below any scan's noise
    CLI::Option* enu_option = nullptr;
    CLI::Option* geoid_option = nullptr;
    std::vector<CLI::Option*> lod_options;

    //! Checks what can be checked before any work: the format against the output's name, options that
    //! the format ignores, --enu's numbers. `lods_command`: the `lods` command (mesh files only).
    std::vector<double> tolerances() const
    {
        return tolerance_list.empty() ? std::vector<double>{} : parse_numbers(tolerance_list, ',', "--lod-tolerances");
    }

    void validate(const fs::path& out, bool lods_command) const
    {
        const std::string ext = lower_extension(out);
        if (lods_command) {
            // Its --format names the level files' format (the option's own check): nothing to match.
        } else if (format == "lod-glb" && ext != ".glb") {
            throw UsageError(out.string() + ": --format lod-glb writes a .glb file");
        } else if (!format.empty() && !lod_set() && ext != "." + format) {
            throw UsageError(out.string() + ": --format " + format + " does not match the file's extension");
        } else if (format == "3dtiles" && is_mesh_extension(ext)) {
            throw UsageError(out.string() + ": --format 3dtiles writes a directory; this name is a " + ext +
                             " file's (drop the extension, or --format)");
        }
        if (!lods_command && !lod_set())
            for (const CLI::Option* o : lod_options)
                if (given(o))
                    throw UsageError(o->get_name() + ": applies to LOD sets (--format 3dtiles or lod-glb), not one mesh");
        if (format != "3dtiles" && (given(enu_option) || given(geoid_option)))
            throw UsageError(std::string(given(enu_option) ? "--enu" : "--geoid-height") +
                             ": places a 3D Tiles set on the globe; it has no effect on other formats");
        const std::vector<double> tolerances = this->tolerances();
        for (std::size_t i = 1; i < tolerances.size(); ++i)
            if (!(tolerances[i] < tolerances[i - 1]))
                throw UsageError("--lod-tolerances: must decrease strictly, coarse to fine");
        if (!enu.empty())
            enu_anchor();
        if (!(std::abs(geoid_height) <= 1e4))
            throw UsageError("--geoid-height: expected metres within +-10000 (the geoid stays within about 110 m)");
    }

    //! --enu's LON, LAT, HEIGHT. \throw UsageError unless three numbers in range.
    std::array<double, 3> enu_anchor() const
    {
        const auto v = parse_numbers(enu, ',', "--enu");
        if (v.size() != 3 || std::abs(v[1]) > 90 || std::abs(v[0]) > 180 || std::abs(v[2]) > 1e7)
            throw UsageError("--enu: expected LON,LAT,HEIGHT with |LON| <= 180, |LAT| <= 90 and |HEIGHT| <= 1e7 m");
        return {v[0], v[1], v[2]};
    }

    //! Whether the output is a LOD set (the formats stored levels serve).
    bool lod_set() const { return format == "3dtiles" || format == "lod-glb"; }

    LodSetOptions options(const MeshArgs& mesh_args) const
    {
        LodSetOptions o;
        o.max_tile_triangles = max_tile_triangles;
        o.levels = levels;
        o.tolerances = tolerances();
        o.mesh = mesh_args.options();
        return o;
    }
};

// "meshing levels 2/4" on stderr while a LOD set is made (a terminal only; the last call clears it).
void show_level_progress(LodSetOptions& o, const Globals& g)
{
    if (!g.progress())
        return;
    o.progress = [](std::size_t done, std::size_t total) {
        if (done < total)
            std::fprintf(stderr, "\rmeshing levels %zu/%zu (the finest takes longest)", done, total);
        else
            std::fprintf(stderr, "\r%60s\r", "");
    };
}

// A noisy sample's levels end at its noise floor, above the leaves (hierarchy.h): say so, once.
void note_noise_floor(const Hierarchy& h, const LodSet& set)
{
    if (set.levels.empty() || max_noise_floor(h) <= 0)
        return;
    const std::size_t finest = cut_by_tolerance(h, 0.0).size();
    // At the floor: the last level has about the floor cut's tiles (small objects refined while meshing
    // can add some; a set that stopped a level or more above has a half or less).
    const std::size_t last = set.levels.back().cut.size();
    if (finest < h.leaf_count() && 3 * last >= 2 * finest && 2 * last <= 3 * finest) {
        char what[160];
        std::snprintf(what, sizeof what, "the levels end at the noise floor (%zu tiles, not the %zu leaves)", finest,
                      h.leaf_count());
        std::printf("%s\n", noise_note(h, what).c_str());
    }
}

// Levels asked for (--levels N, --lod-tolerances) that the hierarchy cannot give apart: a level whose
// cut is no finer than the one before is left out (below the build's tolerance every cut is the
// leaves). Say so rather than write fewer levels silently (QA round 28b: --levels 6 gave 4).
void note_fewer_levels(const Hierarchy& h, const LodSetOptions& options, const LodSet& set)
{
    const std::size_t asked = options.tolerances.empty() ? options.levels : options.tolerances.size();
    if (asked == 0 || set.levels.size() >= asked)
        return;
    std::printf("note: %zu levels asked, %zu made: the others' cuts were no finer than the level before (the "
                "finest cut has %zu tiles)\n",
                asked, set.levels.size(), cut_by_tolerance(h, 0.0).size());
}

// A tileset without --enu is placed at its input coordinates, taken as ECEF metres. Input far from the
// origin but not on the Earth's surface in ECEF (projected coordinates such as UTM, or a local survey
// grid) would then float inside the globe of a web viewer: say how to place it.
void note_placement(const Hierarchy& h, const ExportArgs& e, bool georeferenced)
{
    if (!e.enu.empty() || georeferenced)
        return;
    const double r = norm(h.bbox().centre() + h.cloud.origin);
    const double earth = 6371000.0;
    if (r > 100000.0 && std::abs(r - earth) > 30000.0)
        std::printf("note: the tileset is placed at its input coordinates as ECEF metres, %.0f km from the "
                    "Earth's centre (projected coordinates such as UTM?); to put it on the globe give the input's "
                    "CRS (--crs EPSG:N on build or reconstruct), or --enu LON,LAT,HEIGHT for local east-north-up "
                    "metres\n",
                    r / 1000.0);
}

// The CRS that `text` names when it can place a tileset on the globe; otherwise nullopt and `why`.
std::optional<ProjectedCrs> usable_crs(const std::string& text, std::string& why)
{
    try {
        return parse_crs(text);
    } catch (const InvalidInput& e) {
        why = e.what();
        return std::nullopt;
    }
}

// One line for `info`: the CRS's name and whether 3D Tiles can be placed by it.
std::string crs_summary(const std::string& crs)
{
    std::string why;
    if (const std::optional<ProjectedCrs> c = usable_crs(crs, why))
        return crs_label(*c) + ": 3D Tiles are placed on the globe by it";
    return crs_label(crs) + " (not used: " + why + ")";
}

// Once the model is known: --up y says the input's y is up, where a model's CRS has z up (a single
// glTF of a georeferenced terrain was written on its side, QA round 64). A tileset placed by --enu
// instead of the model's CRS takes --up as given.
void check_up_axis(const Hierarchy& h, const OutputArgs& o)
{
    if (o.up != "y" || h.cloud.crs.empty())
        return;
    std::string why;
    const std::optional<ProjectedCrs> crs = usable_crs(h.cloud.crs, why);
    throw UsageError("--up y: the model's CRS (" + (crs ? crs_label(*crs) : crs_label(h.cloud.crs)) + ") has z up; leave --up out");
}

// What the levels of a LOD set depend on, in this tool's terms (the level and mesh options, the noise
// floor switch): levels stored in a model are reused only when an export asks for the same.
std::string level_recipe(const ExportArgs& e, const MeshArgs& m, const Globals& g)
{
    char number[32];
    auto real = [&](double v) {
        std::snprintf(number, sizeof number, "%.17g", v);
        return std::string(number);
    };
    std::string tolerances;
    for (double t : e.tolerances())
        tolerances += (tolerances.empty() ? "" : ",") + real(t);
    return std::string("mrtile=") + MRTILE_VERSION + " max-tile-triangles=" + std::to_string(e.max_tile_triangles) + " levels=" + std::to_string(e.levels) +
           " lod-tolerances=" + tolerances + " below-noise=" + (g.below_noise ? "1" : "0") + " alpha=" + real(m.alpha) +
           " height-field=" + m.height_field + " keep-steps=" + (m.keep_steps ? "1" : "0") +
           " refine-fans=" + real(m.refine_fans) + " fit-rounds=" + std::to_string(m.fit_rounds) +
           " no-colors=" + (m.no_colors ? "1" : "0") + " close-holes=" + std::to_string(m.close_holes) +
           (m.thin_walls ? " thin-walls=1" : ""); // only when on: recipes stored without the option still match
}

// Levels stored in a model, on their way into an export, and (--store-levels) those the export meshed,
// on their way back into the model.
struct LevelStore
{
    StoredLevels from_model;
    bool keep = false;
    StoredLevels kept; // its recipe is set when the export meshes levels that are to be kept
    // Where kept levels go: the model file, with the hierarchy as the model holds it (its own CRS, not
    // an export's --crs) and these save options.
    fs::path model;
    Hierarchy* hierarchy = nullptr;
    std::string model_crs;
    SaveOptions save;
    std::size_t stored = 0; // levels stored

    // Stores the LOD set's levels in the model before the export writes anything, so that a model that
    // cannot be written leaves no output behind. The levels are lent to the save (moved, not copied:
    // a vector's move keeps its meshes where they are) and handed back.
    void store(std::vector<LodLevel>& levels)
    {
        if (!keep || kept.recipe.empty())
            return;
        assert(hierarchy != nullptr && !model.empty());
        kept.levels = std::move(levels);
        const std::string export_crs = hierarchy->cloud.crs;
        hierarchy->cloud.crs = model_crs;
        SaveOptions options = save;
        options.levels = &kept;
        try {
            save_model(*hierarchy, model, options);
        } catch (...) {
            hierarchy->cloud.crs = export_crs;
            levels = std::move(kept.levels);
            throw;
        }
        hierarchy->cloud.crs = export_crs;
        levels = std::move(kept.levels);
        stored = levels.size();
        std::printf("stored the %s in %s: exports with the same options reuse them\n", count_of(stored, "level", "levels").c_str(),
                    model.string().c_str());
    }
};

// Faces of all levels together.
std::size_t level_faces(const std::vector<LodLevel>& levels)
{
    std::size_t faces = 0;
    for (const LodLevel& level : levels)
        faces += level.mesh.n_faces();
    return faces;
}

// The levels of an export's LOD set: the model's stored ones when they were made with the same options,
// else meshed now.
std::vector<LodLevel> lod_levels(const Hierarchy& h, LodSetOptions options, const std::string& recipe, LevelStore& store,
                                 const Globals& g)
{
    std::vector<LodLevel> levels;
    StoredLevels& stored = store.from_model;
    if (!stored.levels.empty() && stored.recipe == recipe) {
        std::printf("using the %s stored in the model (no meshing)\n", count_of(stored.levels.size(), "level", "levels").c_str());
        levels = std::move(stored.levels);
    } else {
        if (!stored.levels.empty())
            std::printf("note: the model's stored levels were made with other options (%s); meshing the levels again\n",
                        stored.recipe.c_str());
        show_level_progress(options, g);
        levels = make_lod_levels(h, options);
        if (store.keep)
            store.kept.recipe = recipe; // LevelStore::store saves them once the set is made
    }
    return levels;
}

// The model's CRS when it can place a tileset on the globe; otherwise a note says why not and the
// tileset stays in the input's coordinates.
std::optional<ProjectedCrs> placement_crs(const Hierarchy& h)
{
    if (h.cloud.crs.empty())
        return std::nullopt;
    std::string why;
    const std::optional<ProjectedCrs> crs = usable_crs(h.cloud.crs, why);
    if (!crs)
        std::printf("note: the input's coordinate system cannot place the tileset on the globe (%s)\n", why.c_str());
    return crs;
}

void write_tileset(const Hierarchy& h, const ExportArgs& e, const MeshArgs& m, const OutputArgs& o, const Globals& g, const fs::path& dir,
                   LevelStore& stored)
{
    const auto start = Clock::now();
    TilesetOptions t;
    t.gltf = o.gltf();
    // Placement is settled before the (long) meshing, so that a usage error comes at once.
    std::optional<ProjectedCrs> crs;
    if (!e.enu.empty()) {
        // The files hold positions relative to the model's origin; the transform maps those (not the
        // input's ENU coordinates) to ECEF: ENU to ECEF after the origin's translation. Without it
        // a model whose points lie away from 0 (the origin is their median) landed that far off.
        const std::array<double, 3> v = e.enu_anchor();
        std::array<double, 16> m = enu_to_ecef_transform(v[0], v[1], v[2]);
        // --enu takes the input's coordinates as metres east, north and up of the anchor: a model in a
        // projected CRS (UTM metres) given --enu landed 1,169 km up without a word (QA round 38).
        if (!h.cloud.crs.empty())
            std::printf("note: --enu places the model's coordinates as east-north-up metres at %.7g, %.7g; its own "
                        "coordinate system (%s) is not used (leave --enu out to place the tileset by it)\n",
                        v[0], v[1], one_line(crs_label(h.cloud.crs)).c_str());
        const double away = norm(h.bbox().centre() + h.cloud.origin);
        if (away > 100000.0 && h.cloud.crs.empty()) // with a CRS, the note above says what to do
            std::printf("note: --enu takes the input's coordinates as metres from the anchor: the model's centre lies "
                        "%.0f km from it (projected coordinates? give the input's CRS instead: --crs EPSG:N on build or "
                        "reconstruct)\n",
                        away / 1000.0);
        const Vec3 o = from_output_frame(to_output_frame(h.cloud.origin, t.gltf.up_axis), UpAxis::Z); // tileset frame
        for (int row = 0; row < 3; ++row)
            m[static_cast<std::size_t>(12 + row)] += m[static_cast<std::size_t>(row)] * o.x +
                                                     m[static_cast<std::size_t>(4 + row)] * o.y +
                                                     m[static_cast<std::size_t>(8 + row)] * o.z;
        t.root_transform = m;
    } else {
        crs = placement_crs(h);
    }
    if (crs && t.gltf.up_axis != UpAxis::Z)
        throw UsageError("--up y: the model's CRS (" + crs_label(*crs) + ") has z up; leave --up out");
    // One cause per message (QA round 57: a finite height without a CRS was told "needs a finite value").
    if (e.geoid_height != 0.0 && !std::isfinite(e.geoid_height))
        throw UsageError("--geoid-height: needs a finite value");
    if (e.geoid_height != 0.0 && !crs)
        throw UsageError(e.enu.empty() ? "--geoid-height: the tileset is not placed by a CRS (the model has none; give --crs)"
                                       : "--geoid-height: applies to a tileset placed by a CRS, not by --enu");
    const LodSetOptions options = e.options(m);
    LodSet set = make_lod_tiles(h, lod_levels(h, options, level_recipe(e, m, g), stored, g), options);
    note_noise_floor(h, set);
    note_airborne(set);
    note_fewer_levels(h, options, set);
    stored.store(set.levels);
    Vec3 origin = h.cloud.origin;
    std::optional<GeoPlacement> placed;
    if (crs) {
        placed = georeference(set, h.cloud.origin, h.nodes.front().box, *crs, e.geoid_height);
        t.root_transform = placed->root_transform;
        origin = Vec3{0, 0, 0};
    }
    int bits = o.quantize;
    if (o.draco) {
        // One grid over the whole set, fine enough for its finest levels unless --quantize says otherwise.
        const QuantizationGrid grid = tileset_grid(set);
        t.gltf.draco_options.grid = grid;
        if (!given(o.quantize_option)) {
            bits = tileset_position_bits(h, set, grid, crs ? crs->projection.unit_to_metre : 1.0, o.quantize);
            t.gltf.draco_options.position_bits = bits;
            // At the most Draco takes the step can still be coarser than that (QA round 57: two spheres
            // 200 km apart), and the note after the write says so instead.
            if (bits > o.quantize && bits < kMaxPositionBits)
                std::printf("Draco positions quantized to %d bits (steps of %.3g on the tileset's %.3g-wide grid), under "
                            "half the finest level's accuracy; --quantize N sets it\n",
                            bits, grid.range / (std::ldexp(1.0, bits) - 1.0), grid.range);
        }
    }
    write_lod_tileset(set, origin, dir, t);
    if (o.draco) // one grid over the whole set: the finest level is where a coarse step shows
        note_coarse_quantization(set.levels.back().mesh, bits, dir, t.gltf.draco_options.grid ? t.gltf.draco_options.grid->range : 0.0,
                                 !given(o.quantize_option) && bits == kMaxPositionBits);
    if (placed)
        std::printf("placed on the globe by %s: local east-north-up metres at longitude %.7f, latitude %.7f, "
                    "height %.2f m (WGS 84)\n",
                    one_line(crs_label(*crs)).c_str(), placed->anchor.longitude_deg, placed->anchor.latitude_deg,
                    placed->anchor.height);
    note_placement(h, e, placed.has_value());
    std::size_t contents = 0, triangles = 0, over = 0, largest = 0;
    for (const LodTile& tile : set.tiles)
        if (tile.mesh.n_faces() > 0) {
            ++contents;
            triangles += tile.mesh.n_faces();
            largest = std::max(largest, tile.mesh.n_faces());
            over += tile.mesh.n_faces() > options.max_tile_triangles ? 1 : 0;
        }
    // Said, not silent (QA round 57: a corridor's root held 5,430 triangles at 4,096).
    if (over > 0)
        std::printf("note: %s: %zu of %zu tiles hold more than --max-tile-triangles %zu (up to %zu): regions their level cannot "
                    "split (a cut node's faces stay together; a coarse level cut finer where it was in pieces)\n",
                    dir.string().c_str(), over, contents, options.max_tile_triangles, largest);
    std::printf("wrote %s: %s, %s with content, %zu triangles in all%s (%.2f s)\n",
                (dir / "tileset.json").lexically_normal().string().c_str(), count_of(set.levels.size(), "level", "levels").c_str(),
                count_of(contents, "tile", "tiles").c_str(), triangles, o.draco ? ", Draco" : "", seconds_since(start));
}

// One .glb holding every level (MSFT_lod), for viewers without 3D Tiles.
void write_lod_glb(const Hierarchy& h, const ExportArgs& e, const MeshArgs& m, const OutputArgs& o, const Globals& g, const fs::path& out,
                   LevelStore& stored)
{
    const auto start = Clock::now();
    check_up_axis(h, o);
    LodSetOptions options = e.options(m);
    options.tileset = false;
    LodSet set = make_lod_tiles(h, lod_levels(h, options, level_recipe(e, m, g), stored, g), options);
    note_noise_floor(h, set);
    note_airborne(set);
    note_fewer_levels(h, options, set);
    stored.store(set.levels);
    std::vector<const Mesh*> fine_to_coarse;
    for (std::size_t l = set.levels.size(); l-- > 0;)
        fine_to_coarse.push_back(&set.levels[l].mesh);
    GltfLodOptions lod_options;
    lod_options.gltf = o.gltf();
    write_glb_lods(fine_to_coarse, h.cloud.origin, out, lod_options);
    if (o.draco)
        note_coarse_quantization(set.levels.back().mesh, o.quantize, out);
    std::printf("wrote %s: %s in one file (MSFT_lod) (%.2f s)\n", out.string().c_str(), count_of(set.levels.size(), "level", "levels").c_str(),
                seconds_since(start));
}

void write_lods(const Hierarchy& h, const ExportArgs& e, const MeshArgs& m, const OutputArgs& o, const Globals& g, const fs::path& dir)
{
    const auto start = Clock::now();
    check_up_axis(h, o);
    LodSetOptions options = e.options(m);
    options.tileset = false;
    // A LOD chain for renderers starts at a few thousand triangles, not at what fits one 3D Tiles tile.
    options.first_level_triangles = std::min<std::size_t>(options.max_tile_triangles, 4096);
    show_level_progress(options, g);
    const LodSet set = make_lod_set(h, options);
    note_noise_floor(h, set);
    note_airborne(set);
    note_fewer_levels(h, options, set);
    // Measure first: a level is kept only where its measured mean error is below the one of the coarser
    // level kept before it, so that the set is consistent (a coarser level is never more accurate than a
    // finer one). Where the finest cuts of a scan are too fine for its sampling, such levels would only
    // add faces. A level left out does not end the set: the finer ones are still compared (QA round 60:
    // a level 2.6% worse than the one before ended a chain whose next level was 10% better).
    // Every level's mean is over the same points: those the finest level's mesh is not far from. Strays
    // far off are as far from every level, and their share of the mean moved more than a finer level
    // gains (QA round 57); counted far level by level, a level that left more points out looked more
    // accurate for it (QA round 60: 0, 0, 19, 281, 258 and 281 far points).
    std::vector<QualityReport> quality;
    std::vector<std::size_t> kept, left_out; // indices into set.levels
    if (!set.levels.empty()) {
        std::vector<char> far;
        QualityOptions finest_options;
        finest_options.far_points_found = &far;
        QualityReport finest = measure_quality(h, set.levels.back().cut, set.levels.back().mesh, finest_options);
        QualityOptions same_points;
        same_points.far_points = far.empty() ? nullptr : &far;
        for (std::size_t k = 0; k < set.levels.size(); ++k) {
            QualityReport q = k + 1 == set.levels.size() ? std::move(finest)
                                                         : measure_quality(h, set.levels[k].cut, set.levels[k].mesh, same_points);
            if (!quality.empty() && q.point_to_mesh.near_mean > quality.back().point_to_mesh.near_mean) {
                left_out.push_back(k);
                continue;
            }
            kept.push_back(k);
            quality.push_back(std::move(q));
        }
    }
    // Level 0's budget, said where it is not met (QA round 57: a corridor's level 0 held 5,430 faces
    // against 3,072, with no word): no coarser cut fits it that the set can use (one tile's faces stay
    // together; a level in pieces or with more loops than the finest is cut finer, lod_set.h).
    if (!set.levels.empty() && options.tolerances.empty() && options.levels == 0 &&
        set.levels.front().mesh.n_faces() > options.first_level_triangles * 3 / 4)
        std::printf("note: level 0 has %zu faces, over its budget of %zu (three quarters of min(--max-tile-triangles, "
                    "4096)): no coarser cut that the set can use fits it\n",
                    static_cast<std::size_t>(set.levels.front().mesh.n_faces()), options.first_level_triangles * 3 / 4);
    // Built aside and swapped in whole, as a tileset is: a chain with fewer levels than the one it
    // replaces left that one's finer levels beside it (QA).
    const TemporaryDirectory temporary(dir);
    const fs::path& built = temporary.path();
    nlohmann::json index = nlohmann::json::array();
    const std::string ext = lower_extension(dir / ("x." + (e.format.empty() ? std::string("ply") : e.format)));
    for (std::size_t level = 0; level < quality.size(); ++level) {
        const LodLevel& l = set.levels[kept[level]];
        const QualityReport& q = quality[level];
        const std::string name = "level" + std::to_string(level) + ext;
        temporary.write([&] { write_any_mesh(l.mesh, h.cloud.origin, built / name, o, dir / name); });
        index.push_back({{"level", level}, {"file", name}, {"tolerance", l.tolerance}, {"tiles", l.cut.size()},
                         {"faces", l.mesh.n_faces()}, {"geometric_error", l.geometric_error},
                         {"mean_error", q.point_to_mesh.near_mean}, {"max_error", q.point_to_mesh.max},
                         {"far_points", q.point_to_mesh.far},
                         {"mesh_to_points_max", q.mesh_to_points.max}, {"e_rms", q.e_rms},
                         // A level's own loops and pieces: one more than the finest's is seen through in a
                         // viewer (QA round 43: the rocker arm's level 0 kept a 26-edge loop, said nowhere).
                         {"boundary_loops", q.topology.boundary_loops}, {"components", q.topology.components},
                         {"genus", q.topology.genus}});
        const std::string far = q.point_to_mesh.far == 0 ? std::string()
                                                          : " (" + std::to_string(q.point_to_mesh.far) +
                                                                " points far from the finest level, strays or pieces left out: in the max, not the mean)";
        std::printf("level %zu: tolerance %.3g, %s, %zu faces, %s, %s, genus %d, mean/max distance %.3g/%.3g%s\n",
                    level, l.tolerance, count_of(l.cut.size(), "tile", "tiles").c_str(), static_cast<std::size_t>(l.mesh.n_faces()),
                    count_of(q.topology.boundary_loops, "boundary loop", "boundary loops").c_str(),
                    count_of(q.topology.components, "component", "components").c_str(), q.topology.genus,
                    q.point_to_mesh.near_mean, q.point_to_mesh.max, far.c_str());
    }
    if (!left_out.empty()) {
        std::string tolerances;
        for (const std::size_t k : left_out) {
            char number[32];
            std::snprintf(number, sizeof number, "%.3g", set.levels[k].tolerance);
            tolerances += (tolerances.empty() ? "" : ", ") + std::string(number);
        }
        std::printf("left out %zu of %zu levels (tolerance %s): each measured a higher mean error than the coarser level kept "
                    "before it\n",
                    left_out.size(), set.levels.size(), tolerances.c_str());
    }
    temporary.write([&] { write_file_atomically(built / "lods.json", index.dump(2) + "\n"); });
    replace_directory(built, dir, "LOD chain");
    std::printf("wrote %s and %zu levels (%.2f s)\n", (dir / "lods.json").lexically_normal().string().c_str(), quality.size(), seconds_since(start));
}

// The options every producing command shares, and the one place that picks the writer.
struct ProduceArgs
{
    CutArgs cut;
    MeshArgs mesh;
    OutputArgs output;
    ExportArgs exp;

    //! `with_cut` false: the `lods` command (levels, not a cut; mesh files only).
    void add(CLI::App* cmd, bool with_cut = true)
    {
        if (with_cut)
            cut.add(cmd);
        mesh.add(cmd, with_cut);
        output.add(cmd);
        exp.add(cmd, !with_cut);
    }

    //! Before any work: options that contradict each other or that the output would ignore.
    void validate(const fs::path& out, bool lods_command) const
    {
        cut.validate();
        const std::string written = exp.format == "3dtiles" ? std::string("3dtiles")
                                    : exp.format == "lod-glb" ? std::string(".glb")
                                    : lods_command ? "." + (exp.format.empty() ? std::string("ply") : exp.format)
                                                   : std::string();
        output.validate(out, written);
        exp.validate(out, lods_command);
        if (exp.lod_set() && cut.any_given())
            throw UsageError("cut options (--tolerance, --error, --tau, --tiles, --triangles, --focus, --camera) choose one mesh; "
                             "a LOD set's levels are chosen by --levels or --lod-tolerances");
        if (exp.lod_set() && !mesh.stats_json.empty()) // lods has no --stats-json: its lods.json has the levels'
            throw UsageError("--stats-json: describes one mesh; not a LOD set");
        if (lods_command && mesh.no_quality)
            throw UsageError("--no-quality: lods measures every level (a finer level whose measured mean error is higher than the one kept before it is left out)");
        if (exp.lod_set() && mesh.no_quality)
            throw UsageError("--no-quality: a LOD set's levels are not measured; it skips the measurement of one mesh");
        // Accepted and ignored until QA round 48: the levels of a LOD set are mended by whole cuts.
        for (const CLI::Option* o : {mesh.crack_option, mesh.crossing_option, mesh.hole_option})
            if (exp.lod_set() && given(o))
                throw UsageError(o->get_name() + ": mends one mesh; a LOD set's levels are mended by finer whole cuts instead");
    }

    //! `stored`: levels stored with the model (reused when made with the same options); with
    //! stored.keep, the levels meshed here are stored in stored.model before anything is written.
    void write(const Hierarchy& h, const Globals& g, const fs::path& out, LevelStore& stored) const
    {
        if (exp.format == "3dtiles")
            write_tileset(h, exp, mesh, output, g, out, stored);
        else if (exp.format == "lod-glb")
            write_lod_glb(h, exp, mesh, output, g, out, stored);
        else
            mesh_and_write(h, cut, mesh, output, out);
    }
};

// How messages name the input: its file, or the first file and how many more.
std::string inputs_name(const std::vector<fs::path>& points)
{
    std::string name = points.front().string();
    if (points.size() > 1)
        name += " (and " + std::to_string(points.size() - 1) + " more file" + (points.size() > 2 ? "s" : "") + ")";
    return name;
}

// Scans a .conf lists but the folder lacks: named, since leaving them out changes the model.
void note_missing_scans(const std::vector<fs::path>& points)
{
    for (const fs::path& path : points) {
        if (!is_scan_list(path))
            continue;
        std::string missing;
        std::size_t count = 0;
        for (const ScanPlacement& scan : read_scan_list(path))
            if (scan.missing)
                missing += (count++ == 0 ? "" : ", ") + scan.path.filename().string();
        if (count > 0)
            std::printf("note: %s: %zu listed scan%s missing, left out: %s\n", path.string().c_str(), count,
                        count > 1 ? "s" : "", missing.c_str());
    }
}

// Float32 coordinates too far from the origin for the object (see CoarseCoordinates): the points
// merged or stepped before reading began, and no option here brings them back; the file's export can.
void note_coarse_coordinates(const PointCloud& cloud)
{
    for (const CoarseCoordinates& c : cloud.coarse_coordinates)
        std::printf("note: %s: float32 coordinates about %.0f from the origin are only ~%.2g apart, %.2g%% of the "
                    "object's size; export the scan with double coordinates or shifted near the origin\n",
                    c.file.c_str(), c.magnitude, c.spacing, 100 * c.spacing / c.extent);
}

// A file's own CRS that cannot place a tileset: said at once, not only when exporting.
void note_unusable_crs(const std::string& crs, const std::string& name)
{
    std::string why;
    if (!usable_crs(crs, why))
        std::printf("note: %s: its coordinate system cannot place 3D Tiles on the globe (%s)\n", name.c_str(), why.c_str());
}

// --crs: "EPSG:N", WKT, or a file holding WKT (the .prj beside a shapefile, a .wkt); refused unless
// it is a CRS we can place on the globe (asked for explicitly, it should do what it says).
std::string crs_argument(const std::string& arg)
{
    std::string text = arg;
    std::error_code ec;
    // WKT has brackets and an EPSG code a colon (a bare number gets its own hint from parse_crs);
    // anything else that names no file was meant as one.
    const bool file_like = arg.find_first_of("[(:") == std::string::npos &&
                           arg.find_first_not_of("0123456789 ") != std::string::npos;
    if (file_like && !fs::exists(arg, ec))
        throw IoError(arg + ": no such file (--crs takes EPSG:N, WKT, or a .prj/.wkt file holding WKT)");
    if (fs::is_regular_file(arg, ec)) {
        // A .prj is a line of WKT; a file of megabytes is something else given by mistake.
        if (fs::file_size(arg, ec) > (1u << 20))
            throw IoError(arg + ": too large for a CRS file (over 1 MB; --crs takes a .prj/.wkt file holding WKT)");
        std::ifstream in(arg, std::ios::binary);
        text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        if (!in && !in.eof())
            throw IoError(arg + ": cannot read the CRS file");
        while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
            text.pop_back();
    }
    std::string why;
    if (!usable_crs(text, why))
        throw UsageError("--crs: " + why);
    return text;
}

Hierarchy build_from_points(const std::vector<fs::path>& points, const BuildArgs& args, const Globals& g)
{
    const auto start = Clock::now();
    ReadOptions read;
    read.skip_missing_scans = args.skip_missing_scans;
    read.max_points = args.max_points;
    if (args.skip_missing_scans)
        note_missing_scans(points);
    std::optional<Vec3> viewpoint; // checked before the (possibly long) read
    const std::string crs = args.crs.empty() ? std::string() : crs_argument(args.crs);
    if (!args.viewpoint.empty()) {
        const auto v = parse_numbers(args.viewpoint, ',', "--viewpoint");
        if (v.size() != 3)
            throw UsageError("--viewpoint: expected X,Y,Z, got '" + args.viewpoint + "'");
        viewpoint = Vec3{v[0], v[1], v[2]};
    }
    PointCloud cloud = read_points(points, read);
    note_coarse_coordinates(cloud);
    if (viewpoint)
        cloud.viewpoint = *viewpoint - cloud.origin;
    if (!crs.empty()) {
        // --crs is taken as given (a file's CRS record can be wrong), but a user who meant to reproject
        // should hear that nothing moves: the coordinates stay those of the files' own system.
        if (!cloud.crs.empty() && crs_differ(cloud.crs, crs))
            std::printf("note: --crs %s replaces the coordinate system of %s (%s); the points are not reprojected\n",
                        one_line(crs_label(crs)).c_str(), one_line(inputs_name(points)).c_str(), one_line(crs_label(cloud.crs)).c_str());
        cloud.crs = crs;
    } else if (!cloud.crs.empty()) {
        note_unusable_crs(cloud.crs, inputs_name(points));
    }
    const std::size_t n = cloud.size();
    // Duplicates go before the outlier test: a point repeated k times is its own k-1 nearest neighbours.
    std::size_t duplicates = 0;
    if (args.remove_outliers && !args.keep_duplicates)
        duplicates = n - remove_duplicates(cloud).size();
    const std::size_t removed = args.remove_outliers ? remove_outliers(cloud) : 0;
    Hierarchy h = build_hierarchy(std::move(cloud), args.options(g));
    if (g.progress())
        std::fprintf(stderr, "\r%60s\r", "");
    // Before the model is saved or meshed: a million random points took 236 s to mesh into 1,640 pieces
    // crossing each other 26,192 times (session 57).
    if (!args.allow_volume)
        if (const SampleDimension d = sample_dimension(h); d.fills_volume) {
            char what[360];
            std::snprintf(what, sizeof what,
                          "the points fill a volume instead of sampling a surface (local dimension %.2f, where a "
                          "surface measures 2 and a volume 3; leaves %.2f times as thick as wide): random points, "
                          "vegetation, or noise of several percent of the object's size have no surface to mesh "
                          "(--allow-volume builds anyway)",
                          d.mean_dimension, d.leaf_roughness);
            throw InvalidInput(what);
        }
    duplicates += h.info.duplicates_merged;
    std::printf("read and built %s: %s", inputs_name(points).c_str(), count_of(n, "point", "points").c_str());
    if (duplicates > 0)
        std::printf(" (%s merged)", count_of(duplicates, "duplicate", "duplicates").c_str());
    if (args.remove_outliers)
        std::printf(" (%s removed)", count_of(removed, "outlier", "outliers").c_str());
    if (h.info.denoised)
        std::printf(args.denoise == "on" ? " (denoised)" : " (noisy: denoised)");
    std::printf(", %s, %s, depth %u (%.2f s)\n", count_of(h.nodes.size(), "node", "nodes").c_str(),
                count_of(h.leaf_count(), "leaf", "leaves").c_str(), h.max_depth(), seconds_since(start));
    return h;
}

// Library errors about the data (not the file) do not know which input they came from: name it.
template <typename Work>
void naming_input(const std::string& input, Work work)
{
    try {
        work();
    } catch (const InvalidInput& e) {
        const std::string what = e.what();
        if (what.rfind(input, 0) == 0)
            throw;
        throw InvalidInput(input + ": " + what);
    } catch (const std::bad_alloc&) {
        // Named like any other error of the input (QA round 34: "mrtile: error: out of memory", no file).
        throw IoError(input + ": out of memory while working on it (more points, or a finer cut, than this "
                              "machine's memory holds)");
    }
}
template <typename Work>
void naming_input(const fs::path& input, Work work)
{
    naming_input(input.string(), work);
}
// Several inputs: an error that names one of them already is left as it is ("b.xyz: line 1", not
// "a.xyz (and 1 more file): b.xyz: line 1", as build and reconstruct put it until QA round 29).
template <typename Work>
void naming_input(const std::vector<fs::path>& inputs, Work work)
{
    try {
        work();
    } catch (const InvalidInput& e) {
        const std::string what = e.what();
        for (const fs::path& input : inputs)
            if (what.rfind(input.string() + ":", 0) == 0)
                throw;
        naming_input(inputs_name(inputs), [&] { throw; }); // rethrown to be named by all the inputs
    } catch (const std::bad_alloc&) {
        naming_input(inputs_name(inputs), [&] { throw; });
    }
}

// A model and its stored levels, which are a cache: where only they are damaged (the hierarchy loads),
// the model is used without them and a note says why. `info` failed on such a file and a default
// export stopped, while `mesh` and `lods`, which do not read the levels, used it (QA round 34).
// `damage` (if given) gets what is wrong with the levels, or stays empty.
Model load_model_or_without_levels(const fs::path& path, std::string* damage = nullptr)
{
    try {
        return load_model_with_levels(path);
    } catch (const IoError& levels) {
        Model model;
        model.hierarchy = load_model(path); // throws if the damage is not the levels' alone
        // The loader's words are of a whole model ("not a valid .mrt model: stored level 0: ..."): name
        // the levels' part only, since the model itself is used.
        std::string cause = levels.what();
        if (const std::size_t at = cause.find("stored level"); at != std::string::npos)
            cause = cause.substr(at);
        std::fprintf(stderr, "note: %s: its stored levels are damaged (%s); the model is used without them\n",
                     path.string().c_str(), cause.c_str());
        if (damage)
            *damage = cause;
        return model;
    }
}

int run_info(const fs::path& model, bool json)
{
    std::string levels_damage;
    const Model contents = load_model_or_without_levels(model, &levels_damage);
    const Hierarchy& h = contents.hierarchy;
    const StoredLevels& stored = contents.levels;
    const std::size_t stored_faces = level_faces(stored.levels);
    const BoundingBox box = h.bbox();
    const Vec3 lo = box.min + h.cloud.origin, hi = box.max + h.cloud.origin;
    const bool timed = std::isfinite(h.info.build_seconds);
    const std::string criterion = h.info.criterion == Criterion::Tau ? "tau" : "tolerance";
    // Share of the points where the finest cut by tolerance stops short of the leaves at a noise
    // floor. (Counting the leaves with any floor called a clean sample forced through --denoise on
    // 100% noisy: its floors are tiny, under the nodes' own plane distances.)
    const NoiseFloorStops stops = noise_floor_stops(h);
    const std::size_t noisy_points = stops.points;
    const double noisy_share = h.cloud.size() > 0 ? static_cast<double>(noisy_points) / static_cast<double>(h.cloud.size()) : 0.0;
    const double floor_max = h.scale > 0 ? stops.floor_max / h.scale : 0.0;
    // Holes a tile would cover (coverage_gap.h): the largest gap that is a node's error (larger than its
    // plane distance), relative to the scale; cuts by tolerance finer than it keep that hole open.
    double hole_max = 0.0;
    std::size_t hole_nodes = 0;
    for (const Node& n : h.nodes)
        if (gap_dominates(n)) {
            ++hole_nodes;
            hole_max = std::max(hole_max, n.coverage_gap);
        }
    const double hole_share = h.scale > 0 ? hole_max / h.scale : 0.0;
    // With a viewpoint: whether the points are one view from it, as meshing judges it (single_view.h).
    const std::optional<SingleViewStats>& view = h.view;
    if (json) {
        nlohmann::json j;
        j["file"] = model.string();
        j["points"] = h.cloud.size();
        j["nodes"] = h.nodes.size();
        j["leaves"] = h.leaf_count();
        j["depth"] = h.max_depth();
        j["bbox_min"] = vec_json(lo);
        j["bbox_max"] = vec_json(hi);
        j["origin"] = vec_json(h.cloud.origin);
        j["criterion"] = criterion;
        j["criterion_value"] = h.info.criterion_value;
        j["pca_limit"] = h.info.pca_limit;
        j["min_cluster"] = h.info.min_cluster;
        j["reclassify"] = h.info.reclassify;
        j["denoised"] = h.info.denoised;
        // 0: not denoised, or denoised before the moves were stored.
        j["denoise_move"] = h.scale > 0 ? typical_move(h, 0, h.denoise_moves.size()) / h.scale : 0.0;
        j["colors"] = h.cloud.has_colors();
        j["viewpoint"] = h.cloud.viewpoint ? vec_json(*h.cloud.viewpoint + h.cloud.origin) : nlohmann::json(nullptr);
        j["single_view"] = view ? nlohmann::json(view->single_view) : nlohmann::json(nullptr);
        j["hidden_share"] = view ? nlohmann::json(view->hidden_share) : nlohmann::json(nullptr);
        j["crs"] = h.cloud.crs.empty() ? nlohmann::json(nullptr) : nlohmann::json(h.cloud.crs);
        j["build_seconds"] = timed ? nlohmann::json(h.info.build_seconds) : nlohmann::json(nullptr);
        j["scale"] = h.scale;
        j["noise_floor_max"] = floor_max;
        j["noisy_share"] = noisy_share;
        j["hole_max"] = hole_share;
        j["hole_nodes"] = hole_nodes;
        j["stored_levels"] = stored.levels.size();
        j["stored_level_faces"] = stored_faces;
        j["stored_level_recipe"] = stored.levels.empty() ? nlohmann::json(nullptr) : nlohmann::json(stored.recipe);
        j["stored_levels_damage"] = levels_damage.empty() ? nlohmann::json(nullptr) : nlohmann::json(levels_damage);
        // The CRS is kept as the input gave it, and a .prj or a LAS WKT record in Latin-1 ("Zone \xE4")
        // is no UTF-8: dump() threw, and info --json failed with "[json.exception.type_error.316] invalid
        // UTF-8 byte" (QA round qa-fuzz). Such bytes are written as U+FFFD.
        std::printf("%s\n", j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
        return 0;
    }
    std::printf("model       %s\n", model.string().c_str());
    std::printf("points      %zu%s\n", h.cloud.size(), h.cloud.has_colors() ? " (with colours)" : "");
    std::printf("nodes       %zu\nleaves      %zu\ndepth       %u\n", h.nodes.size(), h.leaf_count(), h.max_depth());
    std::printf("bbox min    %s\nbbox max    %s\n", shortest(lo).c_str(), shortest(hi).c_str());
    std::printf("criterion   %s %g, pca limit %u, min cluster %u, reclassify %s\n", criterion.c_str(), h.info.criterion_value,
                h.info.pca_limit, h.info.min_cluster, h.info.reclassify ? "on" : "off");
    std::printf("scale       %s (tolerances are relative to it)\n", shortest(h.scale).c_str());
    if (h.cloud.viewpoint) {
        const Vec3 v = *h.cloud.viewpoint + h.cloud.origin;
        std::printf("viewpoint   %s (open surfaces face it; %s: %.2g%% of the points hidden from it)\n",
                    shortest(v).c_str(), view->single_view ? "one view, so no handles" : "no single view, handles allowed",
                    100.0 * view->hidden_share);
    }
    if (!h.cloud.crs.empty())
        std::printf("crs         %s\n", one_line(crs_summary(h.cloud.crs)).c_str());
    if (h.info.denoised && !h.denoise_moves.empty() && h.scale > 0)
        std::printf("denoised    the points were moved onto the surface before the build, by %.3g of the scale "
                    "(typically); their residual noise floors each region at %g times its points' typical move\n",
                    typical_move(h, 0, h.denoise_moves.size()) / h.scale, kDenoisedFloorShare);
    else if (h.info.denoised)
        std::printf("denoised    the points were moved onto the surface before the build\n");
    // In the words of the notes build and mesh print (QA round 77: "44% of the points are noisy" here,
    // "some points are rough" there, for a sample that is not noisy as a whole).
    if (noisy_points > 0)
        std::printf("noise       %s: %.0f%% of the points lie under noise floors, where cuts by tolerance stop (floors up "
                    "to %.3g of the scale)\n",
                    noise_words(noisy_as_a_whole(h)),
                    100.0 * noisy_share, floor_max);
    else
        std::printf("noise       none found (no noise floor)\n");
    if (hole_nodes > 0)
        std::printf("holes       %zu nodes' tiles would cover holes, the widest %.3g of the scale across its middle: "
                    "cuts by tolerance refine them below that\n",
                    hole_nodes, hole_share);
    else
        std::printf("holes       none under flat tiles\n");
    if (timed)
        std::printf("build time  %.3f s\n", h.info.build_seconds);
    else
        std::printf("build time  not recorded (build with --record-time)\n");
    if (!stored.levels.empty())
        std::printf("levels      %zu stored (%zu faces in all; `export` reuses them with: %s)\n", stored.levels.size(),
                    stored_faces, stored.recipe.c_str());
    else if (!levels_damage.empty())
        std::printf("levels      damaged, not used (see the note; `export --store-levels` stores them again)\n");
    else
        std::printf("levels      none stored (build with --store-levels for fast exports)\n");
    return 0;
}

// What a command writes, checked before any work (outputs_checked): so that an unwritable output
// fails at once, and never after another output of the same command was written.
struct Output
{
    enum class Kind { file, mesh, model, tileset, directory };
    fs::path path;
    Kind kind = Kind::file;
};

// A path as it would be opened: absolute, links resolved as far as it exists. (weakly_canonical alone
// leaves a relative path whose first part does not exist as it is: "o.ply" stayed "o.ply" while
// "./o.ply" became "/cwd/o.ply", and `-o o.ply --stats-json ./o.ply` wrote both into one file, QA
// round 34.)
fs::path resolved(const fs::path& p, std::error_code& ec)
{
    const fs::path absolute = fs::absolute(p, ec);
    if (ec)
        return {};
    return fs::weakly_canonical(absolute, ec);
}

// The same file, or (one of them not there yet) the same path once resolved: a scan a list names but
// that is missing would be read as a scan the next time.
bool same_file(const fs::path& a, const fs::path& b)
{
    std::error_code ec;
    if (fs::equivalent(a, b, ec) && !ec)
        return true;
    const fs::path ra = resolved(a, ec);
    if (ec)
        return false;
    const fs::path rb = resolved(b, ec);
    return !ec && ra == rb;
}

// Whether `file` lies inside the directory `dir` (at any depth), paths resolved as they would be opened.
bool lies_inside(const fs::path& file, const fs::path& dir)
{
    std::error_code ec;
    const fs::path f = resolved(file, ec);
    if (ec)
        return false;
    fs::path d = resolved(dir, ec);
    if (ec)
        return false;
    if (d.filename().empty()) // "DIR/"
        d = d.parent_path();
    const auto [end, unused] = std::mismatch(d.begin(), d.end(), f.begin(), f.end());
    return end == d.end() && f != d;
}

// The files a command reads: its inputs, and the scans that scan lists among them name.
std::vector<fs::path> read_files(const std::vector<fs::path>& inputs)
{
    std::vector<fs::path> files = inputs;
    for (const fs::path& in : inputs)
        if (is_scan_list(in)) {
            std::error_code ec;
            if (!fs::is_regular_file(in, ec))
                continue; // reported when it is read
            for (const ScanPlacement& scan : read_scan_list(in))
                files.push_back(scan.path);
        }
    return files;
}

// An existing lods output directory is replaced as a whole, so it may hold only what `lods` writes
// (lods.json, levelN.EXT): a user's own files in it stop the command before any work.
void check_lods_directory(const fs::path& dir)
{
    check_replaceable_directory(dir, "LOD chain", [](const fs::path& d) {
        std::error_code ec;
        for (const fs::directory_entry& entry : fs::directory_iterator(d, ec)) {
            const std::string name = entry.path().filename().string();
            const std::string stem = entry.path().stem().string();
            const bool ours = entry.is_regular_file(ec) &&
                              (name == "lods.json" ||
                               (stem.size() > 5 && stem.compare(0, 5, "level") == 0 &&
                                std::all_of(stem.begin() + 5, stem.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
                                is_mesh_extension(lower_extension(entry.path()))));
            if (!ours)
                return name;
        }
        if (ec)
            throw IoError(d.string() + ": cannot list it (" + ec.message() + ")");
        return std::string();
    });
    check_writable_directory(dir);
}

void check_outputs(const std::vector<fs::path>& inputs, const std::vector<Output>& outputs)
{
    // The same file twice (a shell glob and its own name, a link to it) would be read twice: every
    // point doubled, merged as duplicates or kept twice with --keep-duplicates (QA round 29).
    for (std::size_t i = 0; i < inputs.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (inputs[j] == inputs[i] || same_file(inputs[j], inputs[i]))
                throw UsageError(inputs[i].string() + ": given twice as an input" +
                                 (inputs[j] == inputs[i] ? std::string() : " (also as " + inputs[j].string() + ")"));
    const std::vector<fs::path> read = read_files(inputs);
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        const Output& o = outputs[i];
        if (o.path.empty())
            continue;
        for (const fs::path& in : read)
            if (same_file(in, o.path))
                throw UsageError(o.path.string() + ": is also an input of this command" +
                                 (std::find(inputs.begin(), inputs.end(), in) == inputs.end() ? " (a scan its list names)" : "") +
                                 "; write to another file");
        // A directory output is replaced as a whole: an input inside it that is named like what the
        // command writes there (a model called tileset.json, level0.ply) was deleted with the old
        // directory (QA round 29); other files already stop the command, naming the file.
        if (o.kind == Output::Kind::tileset || o.kind == Output::Kind::directory) {
            for (const fs::path& in : read)
                if (lies_inside(in, o.path))
                    throw UsageError(o.path.string() + ": holds " + in.string() +
                                     ", an input of this command, and is replaced as a whole; write elsewhere");
            // Nor can the working directory be swapped for another: "-o ." did all the work and then
            // failed with "cannot replace the existing tileset (Device or resource busy)" (QA round 29).
            std::error_code ec;
            const fs::path here = fs::current_path(ec);
            if (!ec && (same_file(here, o.path) || lies_inside(here, o.path)))
                throw UsageError(o.path.string() + ": is the working directory or holds it, and is replaced as a whole; "
                                                   "write to a directory of its own (e.g. -o tiles)");
        }
        if (o.kind == Output::Kind::model && lower_extension(o.path) != ".mrt")
            throw UsageError(o.path.string() + ": a model file's name ends in .mrt");
        if (o.kind == Output::Kind::mesh && !is_mesh_extension(lower_extension(o.path)))
            throw UsageError(o.path.string() + ": " + kMeshExtensionHelp);
        for (std::size_t j = 0; j < i; ++j)
            if (outputs[j].path == o.path || same_file(outputs[j].path, o.path))
                throw UsageError(o.path.string() + ": named for two outputs");
        // The standard output carries what the command says it wrote: an output there would be mixed
        // with those lines (QA round 36: a PLY with "wrote ..." after it).
        // (A character device is let be: a terminal shows both, and /dev/null, where scripts send the
        // lines, may also take an output.)
        struct stat out_stat, path_stat;
        if (::fstat(STDOUT_FILENO, &out_stat) == 0 && !S_ISCHR(out_stat.st_mode) && ::stat(o.path.c_str(), &path_stat) == 0 &&
            out_stat.st_dev == path_stat.st_dev && out_stat.st_ino == path_stat.st_ino)
            throw UsageError(o.path.string() + ": is the standard output, where mrtile says what it wrote; name a file, "
                                               "or another pipe (such as >(...))");
        switch (o.kind) {
        case Output::Kind::file:
        case Output::Kind::mesh:
        case Output::Kind::model: check_writable_file(o.path); break;
        case Output::Kind::tileset: check_tileset_directory(o.path); break;
        case Output::Kind::directory: check_lods_directory(o.path); break;
        }
    }
}

int run(int argc, char** argv)
{
    CLI::App app{"mrtile: point clouds to multiresolution meshes, glTF and 3D Tiles "
                 "(Heckel, Uva, Hamann clustering-based hierarchical surface models)"};
    app.set_version_flag("--version", std::string("mrtile ") + MRTILE_VERSION + "\nheap: " + mrt::tools::heap_setting());
    app.require_subcommand(1);
    app.fallthrough(); // global flags (-q) may follow the command
    // A flag given a value (`--thin-walls=3`, read as a spacing) is a usage error, not "on" (QA: it was
    // accepted as the flag). Subcommands inherit this.
    app.option_defaults()->disable_flag_override();
    Globals g;
    app.add_flag("-q,--quiet", g.quiet, "no progress output");
    app.add_flag("--below-noise", g.below_noise,
                 "let tolerance, region and camera cuts refine below the points' noise level (noisy samples break into pieces there)");
    std::size_t threads = 0;
    app.add_option("--threads", threads, "worker threads (0 = one per hardware thread); output does not depend on it")
        ->check(integer_check(0, 4096))
        ->capture_default_str();

    // build
    auto* build = app.add_subcommand("build", "build the cluster hierarchy of a point cloud into a .mrt model");
    std::vector<fs::path> build_in;
    fs::path build_out;
    BuildArgs build_args;
    bool record_time = false;
    build->add_option("POINTS", build_in,
                      "point files (one or more, merged in absolute coordinates): .ply .las .ptx .pcd .xyz .pts .txt .csv "
                      ".obj .off, optionally .gz, or a .conf scan list")
        ->check(kNonEmpty)->required();
    build->add_option("-o,--output", build_out, "model file to write (.mrt)")->check(kNonEmpty)->required();
    build_args.add(build, "");
    build->add_flag("--record-time", record_time, "store the build time in the model (the file then differs between runs)");
    bool store_levels = false;
    build->add_flag("--store-levels", store_levels,
                    "also mesh the levels a default `export` makes and store them in the model, so that exports of it "
                    "only cut tiles (about a minute per million points; adds about 50-65 bytes per point)");

    // info
    auto* info = app.add_subcommand("info", "describe a .mrt model");
    fs::path info_in;
    bool info_json = false;
    info->add_option("MODEL", info_in, "model file")->check(kNonEmpty)->required();
    info->add_flag("--json", info_json, "one JSON object");

    // mesh
    auto* mesh = app.add_subcommand("mesh", "cut a model and write the mesh");
    fs::path mesh_in, mesh_out;
    CutArgs mesh_cut_args;
    MeshArgs mesh_args;
    OutputArgs mesh_out_args;
    mesh->add_option("MODEL", mesh_in, "model file")->check(kNonEmpty)->required();
    mesh->add_option("-o,--output", mesh_out, "mesh file: .ply .obj .off .stl .om .glb .gltf .drc")->check(kNonEmpty)->required();
    mesh_cut_args.add(mesh);
    mesh_args.add(mesh);
    mesh_out_args.add(mesh);

    // reconstruct
    auto* rec = app.add_subcommand("reconstruct", "build and mesh in one step (or write 3D Tiles with --format 3dtiles)");
    std::vector<fs::path> rec_in;
    fs::path rec_out, rec_model;
    BuildArgs rec_build;
    ProduceArgs rec_args;
    rec->add_option("POINTS", rec_in, "point files (one or more, merged)")->check(kNonEmpty)->required();
    rec->add_option("-o,--output", rec_out, "mesh file, or a directory with --format 3dtiles")->check(kNonEmpty)->required();
    rec->add_option("--model", rec_model, "also save the hierarchy to this .mrt file")->check(kNonEmpty);
    bool rec_store_levels = false;
    rec->add_flag("--store-levels", rec_store_levels,
                  "with --model and a LOD set (--format 3dtiles or lod-glb): also store the levels meshed here in "
                  "the model, so that exports of it only cut tiles");
    rec_build.add(rec, "build-");
    rec_args.add(rec);

    // lods
    auto* lods = app.add_subcommand("lods", "write one mesh per level of detail and a JSON index");
    fs::path lods_in, lods_out;
    ProduceArgs lods_args;
    lods->add_option("MODEL", lods_in, "model file")->check(kNonEmpty)->required();
    lods->add_option("-o,--output", lods_out, "directory")->check(kNonEmpty)->required();
    lods_args.add(lods, false);

    // export
    auto* exp = app.add_subcommand("export", "export a model: 3D Tiles (directory) or one mesh file");
    fs::path exp_in, exp_out;
    ProduceArgs exp_args;
    exp->add_option("MODEL", exp_in, "model file")->check(kNonEmpty)->required();
    exp->add_option("-o,--output", exp_out, "file (.glb .gltf .drc .ply ...) or directory for --format 3dtiles")->check(kNonEmpty)->required();
    exp_args.add(exp);
    std::string exp_crs;
    bool exp_store_levels = false;
    exp->add_flag("--store-levels", exp_store_levels,
                  "LOD sets: store the levels meshed here in MODEL.mrt (rewritten), so that exports with the same "
                  "level and mesh options only cut tiles");
    exp->add_option("--crs", exp_crs,
                    "3D Tiles: the model's coordinate system (EPSG:N, WKT, or a .prj/.wkt file), in place of the "
                    "one stored in it")
        ->check(kNonEmpty);

    // demo
    auto* demo = app.add_subcommand("demo", "the whole pipeline on a built-in genus-3 test shape");
    fs::path demo_out = "out/demo";
    demo->add_option("-o,--output", demo_out, "output directory")->check(kNonEmpty)->capture_default_str();

    // One line, like every other error (CLI11's default adds a second "Run with --help" line).
    app.failure_message([](const CLI::App*, const CLI::Error& e) {
        return "mrtile: usage error: " + one_line(e.what()) + " (see --help)\n";
    });
    // CLI11 reads "-o=x.ply" as -o with the value "=x.ply", and the mesh went to a file of that name
    // (QA round 64); --output=x.ply is the form with "=".
    for (int i = 1; i < argc; ++i)
        if (const std::string arg = argv[i]; arg.rfind("-o=", 0) == 0) {
            std::fprintf(stderr, "mrtile: usage error: '%s': give the output after a space (-o %s) or as --output=%s (see --help)\n",
                         one_line(arg).c_str(), one_line(arg.substr(3)).c_str(), one_line(arg.substr(3)).c_str());
            return 2;
        }
    // A misspelt command would otherwise read "A subcommand is required": name it and the commands.
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--threads") {
            ++i;
            continue;
        }
        if (!arg.empty() && arg[0] == '-') {
            // An option before the command: name it if it is not one of the program's own.
            const std::string name = arg.substr(0, arg.find('='));
            static const char* const own[] = {"-h", "--help", "--version", "-q", "--quiet", "--below-noise", "--threads"};
            if (std::none_of(std::begin(own), std::end(own), [&](const char* o) { return name == o; })) {
                std::fprintf(stderr, "mrtile: usage error: unknown option '%s' (options before the command: "
                                     "--help, --version, --quiet, --below-noise, --threads; see --help)\n", one_line(name).c_str());
                return 2;
            }
            continue;
        }
        const auto all = app.get_subcommands([](const CLI::App*) { return true; });
        std::string names;
        bool known = false;
        for (const CLI::App* sub : all) {
            known = known || sub->get_name() == arg;
            names += (names.empty() ? "" : ", ") + sub->get_name();
        }
        if (!known) {
            std::fprintf(stderr, "mrtile: usage error: unknown command '%s' (commands: %s; see --help)\n", one_line(arg).c_str(), names.c_str());
            return 2;
        }
        break;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // CLI11 checks required options before it complains of unknown ones, so `mesh --bogus x`
        // would say "--output is required": the unknown argument is the likelier mistake, name it.
        const std::vector<std::string> unknown = app.remaining(true);
        if (e.get_exit_code() != 0 && !unknown.empty() && dynamic_cast<const CLI::RequiredError*>(&e)) {
            std::fprintf(stderr, "mrtile: usage error: unknown argument '%s' (see --help)\n", one_line(unknown.front()).c_str());
            return 2;
        }
        if (const std::string what = e.what(); dynamic_cast<const CLI::ArgumentMismatch*>(&e) &&
                                                what.find(" was given a disallowed flag override") != std::string::npos) {
            std::fprintf(stderr, "mrtile: usage error: --%s is a flag and takes no value (see --help)\n",
                         what.substr(0, what.find(' ')).c_str());
            return 2;
        }
        // CLI11 lists unexpected arguments last first ("not expected: 3 --levels", QA round 64): name
        // them in the order they were typed.
        if (dynamic_cast<const CLI::ExtrasError*>(&e) && !unknown.empty()) {
            // A short flag given a value ("-q=1") reaches CLI11 as "-=1": say what --quiet=1 says.
            const bool mangled = std::any_of(unknown.begin(), unknown.end(), [](const std::string& a) { return a.rfind("-=", 0) == 0; });
            for (int k = 1; mangled && k < argc; ++k)
                if (const std::string arg = argv[k]; arg.size() > 2 && arg[0] == '-' && std::isalpha(static_cast<unsigned char>(arg[1])) &&
                                                      arg[2] == '=') {
                    std::fprintf(stderr, "mrtile: usage error: -%c is a flag and takes no value (see --help)\n", arg[1]);
                    return 2;
                }
            std::string list;
            for (const std::string& arg : unknown)
                list += (list.empty() ? "'" : " '") + one_line(arg) + "'";
            std::fprintf(stderr, "mrtile: usage error: unexpected argument%s %s (see --help)\n", unknown.size() == 1 ? "" : "s",
                         list.c_str());
            return 2;
        }
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    set_default_threads(threads);

    const auto output_kind = [](const ProduceArgs& a) {
        return a.exp.format == "3dtiles" ? Output::Kind::tileset : Output::Kind::mesh;
    };
    // Option values first (usage errors, exit 2), then the outputs (exit 1), all before any work.
    if (*mesh) {
        mesh_cut_args.validate();
        mesh_out_args.validate(mesh_out);
    }
    if (*rec)
        rec_args.validate(rec_out, false);
    if (*lods)
        lods_args.validate(lods_out, true);
    if (*exp) {
        exp_args.validate(exp_out, false);
        if (!exp_crs.empty() && exp_args.exp.format != "3dtiles")
            throw UsageError("--crs: places a 3D Tiles set on the globe; it has no effect on other formats");
        if (!exp_crs.empty() && !exp_args.exp.enu.empty())
            throw UsageError("--crs and --enu: both place the tileset; give one");
    }
    // Build options that these inputs or outputs would ignore.
    const auto check_build = [](const BuildArgs& b, const std::vector<fs::path>& inputs) {
        if (b.skip_missing_scans && std::none_of(inputs.begin(), inputs.end(), [](const fs::path& p) { return is_scan_list(p); }))
            throw UsageError("--skip-missing-scans: applies to scan lists (.conf); no input is one");
    };
    if (*build)
        check_build(build_args, build_in);
    // --store-levels stores a LOD set's levels: on one mesh it would do nothing.
    const auto check_store = [](bool store_levels, const ProduceArgs& a) {
        if (store_levels && !a.exp.lod_set())
            throw UsageError("--store-levels: stores a LOD set's levels (--format 3dtiles or lod-glb); this output is one mesh");
    };
    if (*exp)
        check_store(exp_store_levels, exp_args);
    if (*rec) {
        check_store(rec_store_levels, rec_args);
        check_build(rec_build, rec_in);
        // A CRS also shapes the mesh: in the automatic height-field mode a georeferenced cloud's steep
        // tiles are walls, bridged from roof to ground (README: walls of a height field). Only a mode
        // given outright leaves it nothing to do on a mesh that is not placed or stored (an airborne
        // scene as plain XYZ was refused "no effect here", though with the CRS its footprints close).
        if (!rec_build.crs.empty() && rec_model.empty() && rec_args.exp.format != "3dtiles" && rec_args.mesh.height_field != "auto")
            throw UsageError("--crs: places a 3D Tiles set on the globe, is stored with --model, or chooses walls in the automatic "
                             "--height-field mode; it has no effect here");
    }
    if (*build)
        check_outputs(build_in, {{build_out, Output::Kind::model}});
    if (*mesh)
        check_outputs({mesh_in}, {{mesh_out, Output::Kind::mesh}, {mesh_args.stats_json, Output::Kind::file}});
    if (*rec)
        check_outputs(rec_in, {{rec_out, output_kind(rec_args)},
                               {rec_model, Output::Kind::model},
                               {rec_args.mesh.stats_json, Output::Kind::file}});
    if (*lods)
        check_outputs({lods_in}, {{lods_out, Output::Kind::directory}});
    if (*exp) {
        check_outputs({exp_in}, {{exp_out, output_kind(exp_args)}, {exp_args.mesh.stats_json, Output::Kind::file}});
        if (exp_store_levels && exp_args.exp.lod_set())
            check_writable_file(exp_in); // rewritten with the levels: not if read-only
    }
    // A directory the demo made goes again if the demo fails (QA round 66: a full disk left an empty
    // out/demo); one that was there keeps what the demo did not write.
    struct MadeDirectory
    {
        fs::path dir;
        bool keep = false;
        ~MadeDirectory()
        {
            std::error_code ec;
            if (!dir.empty() && !keep)
                fs::remove_all(dir, ec);
        }
    } made;
    if (*demo) {
        // All five outputs before any work: a directory `tiles` of the user's stopped the demo only after
        // it had replaced model.mrt and mesh.ply there (QA round 34).
        std::error_code ec;
        if (!fs::exists(fs::symlink_status(demo_out, ec)))
            made.dir = demo_out;
        ensure_directory(demo_out);
        check_outputs({}, {{demo_out / "model.mrt", Output::Kind::model},
                           {demo_out / "mesh.ply", Output::Kind::mesh},
                           {demo_out / "mesh.json", Output::Kind::file},
                           {demo_out / "mesh.glb", Output::Kind::mesh},
                           {demo_out / "tiles", Output::Kind::tileset}});
    }

    if (*build) {
        Hierarchy h;
        naming_input(build_in, [&] { h = build_from_points(build_in, build_args, g); });
        SaveOptions s;
        s.record_build_time = record_time;
        StoredLevels stored;
        if (store_levels) {
            const auto start = Clock::now();
            if (g.below_noise)
                clear_noise_floor(h); // derived, not saved: only the levels see it
            const ExportArgs e;
            const MeshArgs m;
            LodSetOptions options = e.options(m);
            show_level_progress(options, g);
            naming_input(inputs_name(build_in), [&] { stored.levels = make_lod_levels(h, options); });
            stored.recipe = level_recipe(e, m, g);
            s.levels = &stored;
            std::printf("meshed %zu levels to store (%zu faces in all) (%.2f s)\n", stored.levels.size(),
                        level_faces(stored.levels), seconds_since(start));
        }
        save_model(h, build_out, s);
        // A device or a pipe has no size (QA round 36: "filesystem error: cannot get file size").
        std::error_code size_error;
        const std::uintmax_t bytes = fs::file_size(build_out, size_error);
        if (size_error)
            std::printf("wrote %s\n", build_out.string().c_str());
        else
            std::printf("wrote %s (%ju bytes)\n", build_out.string().c_str(), bytes);
        return 0;
    }
    if (*info)
        return run_info(info_in, info_json);
    // The noise floor is derived when a model is built or loaded; the flag only switches it off.
    auto apply_globals = [&](Hierarchy& h) {
        if (g.below_noise)
            clear_noise_floor(h);
    };
    if (*mesh) {
        Hierarchy h = load_model(mesh_in);
        apply_globals(h);
        naming_input(mesh_in, [&] { mesh_and_write(h, mesh_cut_args, mesh_args, mesh_out_args, mesh_out); });
        return 0;
    }
    if (*rec) {
        if (rec_store_levels && rec_model.empty())
            throw UsageError("--store-levels: needs --model M.mrt (the levels are stored in it)");
        Hierarchy h; // a library error about the points names the inputs, as on `build`
        naming_input(rec_in, [&] { h = build_from_points(rec_in, rec_build, g); });
        apply_globals(h);
        LevelStore store;
        store.keep = rec_store_levels;
        store.model = rec_model;
        store.hierarchy = &h;
        store.model_crs = h.cloud.crs;
        naming_input(inputs_name(rec_in), [&] { rec_args.write(h, g, rec_out, store); });
        // Last, so that a failed command leaves no model either (with --store-levels it is already
        // written, with its levels, before the tileset). A model that cannot be saved (a full disk)
        // takes the output just written with it: exit 1 leaves nothing behind (QA round 57 found the
        // tileset left).
        if (!rec_model.empty() && store.stored == 0) {
            try {
                save_model(h, rec_model);
            } catch (...) {
                std::error_code ec;
                if (fs::is_directory(rec_out, ec) && fs::exists(rec_out / "tileset.json", ec))
                    fs::remove_all(rec_out, ec);
                else if (fs::is_regular_file(rec_out, ec))
                    fs::remove(rec_out, ec);
                throw;
            }
            std::printf("wrote %s\n", rec_model.string().c_str());
        }
        return 0;
    }
    if (*lods) {
        Hierarchy h = load_model(lods_in);
        apply_globals(h);
        naming_input(lods_in, [&] { write_lods(h, lods_args.exp, lods_args.mesh, lods_args.output, g, lods_out); });
        return 0;
    }
    if (*exp) {
        const std::string crs = exp_crs.empty() ? std::string() : crs_argument(exp_crs);
        // Stored levels serve LOD sets only; a single mesh leaves them unread (a second or so per million points).
        const bool lod_set = exp_args.exp.lod_set();
        Model model;
        if (lod_set)
            model = load_model_or_without_levels(exp_in);
        else
            model.hierarchy = load_model(exp_in);
        Hierarchy& h = model.hierarchy;
        const std::string model_crs = h.cloud.crs;
        apply_globals(h);
        if (!crs.empty())
            h.cloud.crs = crs;
        LevelStore store;
        store.from_model = std::move(model.levels);
        store.keep = exp_store_levels;
        // Back into the model as it was loaded (an export's --crs places this tileset only).
        store.model = exp_in;
        store.hierarchy = &h;
        store.model_crs = model_crs;
        store.save.record_build_time = std::isfinite(h.info.build_seconds);
        naming_input(exp_in, [&] { exp_args.write(h, g, exp_out, store); });
        return 0;
    }
    if (*demo) {
        // The built-in default input: the paper's "3Holes"-like genus-3 solid, 40,000 samples.
        const auto start = Clock::now();
        PointCloud cloud = shapes::three_holes(40000);
        shapes::add_noise(cloud, 0.05);
        recenter(cloud);
        std::printf("demo input: genus-3 plate with three holes, %zu samples with slight noise (built in)\n", cloud.size());
        const Hierarchy h = build_hierarchy(std::move(cloud));
        save_model(h, demo_out / "model.mrt");
        std::printf("wrote %s: %zu nodes, %zu leaves, depth %u\n", (demo_out / "model.mrt").string().c_str(), h.nodes.size(),
                    h.leaf_count(), h.max_depth());
        CutArgs cut;
        MeshArgs m;
        m.stats_json = (demo_out / "mesh.json").string();
        OutputArgs o, draco;
        draco.draco = true;
        mesh_and_write(h, cut, m, o, demo_out / "mesh.ply", {AlsoWrite{demo_out / "mesh.glb", draco}});
        std::printf("wrote %s: the mesh's statistics and measured quality (JSON)\n", m.stats_json.c_str());
        o.draco = true;
        ExportArgs e;
        LevelStore none;
        write_tileset(h, e, m, o, g, demo_out / "tiles", none);
        std::printf("demo done in %.2f s: open %s in a 3D Tiles viewer, or %s in any glTF viewer\n", seconds_since(start),
                    (demo_out / "tiles" / "tileset.json").string().c_str(), (demo_out / "mesh.glb").string().c_str());
        made.keep = true;
        return 0;
    }
    return 2;
}

} // namespace

int main(int argc, char** argv)
{
    mrt::tools::use_huge_page_malloc(argv); // returns in the re-executed process (or when it does not apply)
    mrt::install_signal_cleanup(); // an interrupted run leaves no temporary file or directory behind
    try {
        return run(argc, argv);
    } catch (const UsageError& e) {
        std::fprintf(stderr, "mrtile: usage error: %s\n", one_line(e.what()).c_str());
        return 2;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "mrtile: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mrtile: error: %s\n", one_line(e.what()).c_str());
        return 1;
    }
}
