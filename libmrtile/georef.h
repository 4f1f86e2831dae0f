#pragma once
//! \file georef.h
//! \brief Placing projected-coordinate input (UTM and other Transverse Mercator grids) on the globe,
//! without PROJ: the CRS from an EPSG code or WKT, the inverse projection to longitude/latitude, the
//! geodetic → Earth-centred (ECEF) conversion, and a local east-north-up frame.
//! \details 3D Tiles places a tileset with a transform into ECEF metres; input clouds come in a
//! projected CRS. Only Transverse Mercator is supported (the UTM and MGA families cover most survey
//! data), through the Krüger series to sixth order in n (Karney 2011), accurate to far below a
//! millimetre within thousands of kilometres of the central meridian.
//! Datums: only WGS 84 and datums within about 2 m of it (NAD83, ETRS89, GDA94, GDA2020) are accepted,
//! and every one of them is treated as WGS 84 placed on its own ellipsoid: the datum shift (≤ about
//! 2 m, drifting with plate motion) is deliberately ignored, which is below what a viewer on the globe
//! can see but not survey grade. Heights are taken as ellipsoidal: an orthometric (geoid) height is not
//! corrected by the geoid undulation (up to ±100 m), so such a model floats or sinks by that much
//! relative to the globe's ellipsoid while staying correctly shaped.
//! \code
//!   const ProjectedCrs crs = parse_crs("EPSG:32633");            // or the WKT a LAS file carries
//!   const Geodetic g = projected_to_geodetic(crs.projection, 500123.4, 5123456.7, 231.0);
//!   const EnuFrame frame(crs.projection.ellipsoid, g);           // anchor at the model's centre
//!   const Vec3 enu = frame.ecef_to_enu(geodetic_to_ecef(crs.projection.ellipsoid, other));
//! \endcode

#include "libmrtile/vec3.h"

#include <array>
#include <optional>
#include <string>

namespace mrt {

//! A reference ellipsoid (WGS 84 by default; GRS80 differs only in inverse_flattening 298.257222101).
struct Ellipsoid
{
    double a = 6378137.0;                      //!< semi-major axis, metres
    double inverse_flattening = 298.257223563; //!< 1/f; 0 stands for a sphere (as in WKT)
};

//! Transverse Mercator (UTM is one: k0 0.9996, false easting 500000, false northing 0 / 10000000).
//! Angles are in degrees; false easting and northing in the CRS unit (as WKT1 gives them).
struct TransverseMercator
{
    Ellipsoid ellipsoid;
    double central_meridian_deg = 0;
    double latitude_of_origin_deg = 0;
    double scale_factor = 0.9996;
    double false_easting = 500000;
    double false_northing = 0;
    double unit_to_metre = 1.0; //!< projected and vertical unit in metres (1 for metre)
};

struct ProjectedCrs
{
    std::string name; //!< e.g. "WGS 84 / UTM zone 33N" (a WKT name over 80 characters cut to 77 and "...")
    int epsg = 0;     //!< 0 when not known
    TransverseMercator projection;
};

struct Geodetic
{
    double longitude_deg = 0, latitude_deg = 0, height = 0;
};

//! The projected CRS of an EPSG code, or nullopt if the code is not one we support:
//! WGS 84 / UTM 32601–32660 (N) and 32701–32760 (S), NAD83 / UTM 26901–26923, ETRS89 / UTM
//! 25828–25838, GDA94 / MGA 28348–28358 and GDA2020 / MGA 7846–7859.
std::optional<ProjectedCrs> crs_from_epsg(int code);

//! \brief "EPSG:32633" (case-insensitive; "32633" alone is not accepted) or OGC WKT (WKT1 or WKT2).
//! \details WKT: an EPSG id on the outermost projected CRS that crs_from_epsg knows wins; otherwise
//! a Transverse Mercator's parameters, ellipsoid and linear unit are read (missing parameters take
//! the OGC defaults: 0, scale 1), provided its datum is one of those named in the file comment. A
//! compound CRS (COMPD_CS, COMPOUNDCRS) or a BOUNDCRS uses its projected part; a vertical part with
//! a unit other than the horizontal one is refused, since one unit serves both.
//! \throw InvalidInput saying what is not supported or malformed (e.g. "EPSG:2264 is not a supported
//! projected CRS (...)", the datum or projection name, the character where the WKT breaks).
ProjectedCrs parse_crs(const std::string& text);

//! \brief Whether two CRS texts (EPSG:N or WKT, as PointCloud::crs holds them) certainly name two
//! different coordinate systems.
//! \details Two EPSG:N texts differ when their codes do. Otherwise only what parse_crs reads is compared:
//! the EPSG codes when both resolve to one, else the projection, ellipsoid and unit (to rounding a WKT
//! writer may apply). Texts parse_crs refuses (another projection, a geographic CRS) and systems that
//! differ in the datum alone (NAD83 and ETRS89, both on GRS80) are not told apart: false, never a
//! refusal of two spellings of one system.
bool crs_differ(const std::string& a, const std::string& b);

//! A CRS text shortened for a one-line message: EPSG:N as it is; WKT as "WGS 84 / UTM zone 33N
//! (EPSG:32633)" when parse_crs reads it, otherwise its first 60 characters on one line.
std::string crs_label(const std::string& text);

//! The same for a parsed CRS: "WGS 84 / UTM zone 33N (EPSG:32633)", its name alone when no EPSG code is known.
std::string crs_label(const ProjectedCrs& crs);

//! \brief Inverse projection: (easting, northing) in the CRS unit, height in the CRS unit → geodetic
//! (longitude in [-180, 180], height in metres, taken as ellipsoidal).
//! \throw InvalidInput if the coordinates are so far outside the projection that it has no inverse
//! there (a sign of the wrong CRS).
Geodetic projected_to_geodetic(const TransverseMercator& tm, double easting, double northing, double height);

//! \brief Forward projection (for round trips and tests): returns (easting, northing, height) in the
//! CRS unit. \throw InvalidInput for a latitude outside [-90, 90] or a point 90° from the central
//! meridian on the equator (where Transverse Mercator goes to infinity).
Vec3 geodetic_to_projected(const TransverseMercator& tm, const Geodetic& g);

//! Earth-centred, Earth-fixed metres.
Vec3 geodetic_to_ecef(const Ellipsoid& e, const Geodetic& g);

//! A local east-north-up frame at an anchor: ENU metres ↔ ECEF.
class EnuFrame
{
public:
    EnuFrame(const Ellipsoid& e, const Geodetic& anchor);
    //! East, north, up metres of an ECEF point relative to the anchor.
    Vec3 ecef_to_enu(const Vec3& ecef) const;
    //! The other way, as a column-major 4x4 matrix (a 3D Tiles root transform): columns east, north,
    //! up and the anchor in ECEF.
    std::array<double, 16> enu_to_ecef() const;
    const Geodetic& anchor() const;

private:
    Geodetic anchor_;
    Vec3 origin_; //!< the anchor in ECEF
    Vec3 east_, north_, up_;
};

} // namespace mrt
