// Tests of georef.h: Transverse Mercator against known UTM values (quarter meridian, 3° off the
// central meridian), round trips, the southern false northing, ECEF and the ENU frame (including grid
// convergence and scale), the EPSG table, and WKT1/WKT2 parsing, refusals and malformed input.
#include "libmrtile/errors.h"
#include "libmrtile/georef.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace mrt {
namespace {

constexpr double kMm = 1e-3;

TransverseMercator utm(int epsg)
{
    const auto crs = crs_from_epsg(epsg);
    EXPECT_TRUE(crs.has_value()) << epsg;
    return crs ? crs->projection : TransverseMercator{};
}

// The message of the InvalidInput that parse_crs throws, or "" (and a failure) if it does not throw.
std::string parse_error(const std::string& text)
{
    try {
        parse_crs(text);
    } catch (const InvalidInput& e) {
        return e.what();
    }
    ADD_FAILURE() << "parse_crs accepted: " << text.substr(0, 200);
    return {};
}

void expect_same_projection(const TransverseMercator& a, const TransverseMercator& b)
{
    EXPECT_DOUBLE_EQ(a.ellipsoid.a, b.ellipsoid.a);
    EXPECT_DOUBLE_EQ(a.ellipsoid.inverse_flattening, b.ellipsoid.inverse_flattening);
    EXPECT_DOUBLE_EQ(a.central_meridian_deg, b.central_meridian_deg);
    EXPECT_DOUBLE_EQ(a.latitude_of_origin_deg, b.latitude_of_origin_deg);
    EXPECT_DOUBLE_EQ(a.scale_factor, b.scale_factor);
    EXPECT_DOUBLE_EQ(a.false_easting, b.false_easting);
    EXPECT_DOUBLE_EQ(a.false_northing, b.false_northing);
    EXPECT_DOUBLE_EQ(a.unit_to_metre, b.unit_to_metre);
}

const std::string kWgs84Utm33Body =
    R"wkt(PROJCS["WGS 84 / UTM zone 33N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,)wkt"
    R"wkt(AUTHORITY["EPSG","7030"]],AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],)wkt"
    R"wkt(UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AUTHORITY["EPSG","4326"]],)wkt"
    R"wkt(PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],PARAMETER["central_meridian",15],)wkt"
    R"wkt(PARAMETER["scale_factor",0.9996],PARAMETER["false_easting",500000],PARAMETER["false_northing",0],)wkt"
    R"wkt(UNIT["metre",1,AUTHORITY["EPSG","9001"]],AXIS["Easting",EAST],AXIS["Northing",NORTH])wkt";
const std::string kWgs84Utm33 = kWgs84Utm33Body + R"wkt(,AUTHORITY["EPSG","32633"]])wkt";
const std::string kWgs84Utm33NoId = kWgs84Utm33Body + "]";

std::string etrs89_utm32_wkt2(bool with_id)
{
    return R"wkt(PROJCRS["ETRS89 / UTM zone 32N",
    BASEGEOGCRS["ETRS89",
        ENSEMBLE["European Terrestrial Reference System 1989 ensemble",
            MEMBER["European Terrestrial Reference Frame 1989"],
            MEMBER["European Terrestrial Reference Frame 2014"],
            ELLIPSOID["GRS 1980",6378137,298.257222101,
                LENGTHUNIT["metre",1]],
            ENSEMBLEACCURACY[0.1]],
        PRIMEM["Greenwich",0,
            ANGLEUNIT["degree",0.0174532925199433]],
        ID["EPSG",4258]],
    CONVERSION["UTM zone 32N",
        METHOD["Transverse Mercator",
            ID["EPSG",9807]],
        PARAMETER["Latitude of natural origin",0,
            ANGLEUNIT["degree",0.0174532925199433],
            ID["EPSG",8801]],
        PARAMETER["Longitude of natural origin",9,
            ANGLEUNIT["degree",0.0174532925199433],
            ID["EPSG",8802]],
        PARAMETER["Scale factor at natural origin",0.9996,
            SCALEUNIT["unity",1],
            ID["EPSG",8805]],
        PARAMETER["False easting",500000,
            LENGTHUNIT["metre",1],
            ID["EPSG",8806]],
        PARAMETER["False northing",0,
            LENGTHUNIT["metre",1],
            ID["EPSG",8807]]],
    CS[Cartesian,2],
        AXIS["(E)",east,
            ORDER[1],
            LENGTHUNIT["metre",1]],
        AXIS["(N)",north,
            ORDER[2],
            LENGTHUNIT["metre",1]],
    USAGE[
        SCOPE["Engineering survey, topographic mapping."],
        AREA["Europe between 6°E and 12°E."],
        BBOX[38.76,6,84.33,12.01]])wkt" +
           std::string(with_id ? R"wkt(,
    ID["EPSG",25832]])wkt" : "]");
}

TEST(TransverseMercator, CentralMeridianNorthingIsScaledMeridianArc)
{
    const TransverseMercator tm = utm(32633); // central meridian 15°E
    const Vec3 pole = geodetic_to_projected(tm, {15.0, 90.0, 0.0});
    EXPECT_NEAR(pole.y, 0.9996 * 10001965.729, kMm);
    EXPECT_EQ(pole.x, 500000.0);
    const Vec3 mid = geodetic_to_projected(tm, {15.0, 45.0, 0.0});
    EXPECT_NEAR(mid.y, 0.9996 * 4984944.378, kMm);
    EXPECT_EQ(mid.x, 500000.0);
    const Vec3 equator = geodetic_to_projected(tm, {15.0, 0.0, 0.0});
    EXPECT_EQ(equator.x, 500000.0);
    EXPECT_NEAR(equator.y, 0.0, 1e-9);
}

TEST(TransverseMercator, EquatorThreeDegreesOffCentralMeridian)
{
    const TransverseMercator tm = utm(32633);
    const Vec3 east = geodetic_to_projected(tm, {18.0, 0.0, 0.0});
    EXPECT_NEAR(east.x, 833978.557, kMm);
    EXPECT_NEAR(east.y, 0.0, 1e-9);
    const Vec3 west = geodetic_to_projected(tm, {12.0, 0.0, 0.0});
    EXPECT_NEAR(west.x, 166021.443, kMm);
    EXPECT_NEAR(west.y, 0.0, 1e-9);
}

TEST(TransverseMercator, RoundTripsOverAZone)
{
    for (const int epsg : {32633, 32733, 26910, 7855}) {
        const TransverseMercator tm = utm(epsg);
        double worst = 0.0;
        for (double lat = -80.0; lat <= 84.0; lat += 2.0)
            for (double dlon = -3.5; dlon <= 3.5; dlon += 0.25) {
                const Geodetic g{tm.central_meridian_deg + dlon, lat, 123.25};
                const Vec3 p = geodetic_to_projected(tm, g);
                const Geodetic back = projected_to_geodetic(tm, p.x, p.y, p.z);
                worst = std::max({worst, std::fabs(back.latitude_deg - g.latitude_deg),
                                  std::fabs(back.longitude_deg - g.longitude_deg)});
                EXPECT_EQ(back.height, g.height);
            }
        EXPECT_LT(worst, 1e-9) << "EPSG:" << epsg;
    }
}

TEST(TransverseMercator, SouthernZoneUsesFalseNorthing)
{
    const TransverseMercator north = utm(32633), south = utm(32733);
    for (const double lat : {5.0, 33.3, 61.0}) {
        const Vec3 n = geodetic_to_projected(north, {16.5, lat, 0.0});
        const Vec3 s = geodetic_to_projected(south, {16.5, -lat, 0.0});
        EXPECT_NEAR(s.y, 10000000.0 - n.y, 1e-6) << lat;
        EXPECT_NEAR(s.x, n.x, 1e-6) << lat;
        EXPECT_NEAR(projected_to_geodetic(south, s.x, s.y, 0.0).latitude_deg, -lat, 1e-9);
    }
}

TEST(TransverseMercator, LatitudeOfOriginShiftsNorthings)
{
    TransverseMercator tm = utm(32630);
    tm.latitude_of_origin_deg = 49.0;
    tm.false_northing = -100000.0;
    const Vec3 origin = geodetic_to_projected(tm, {tm.central_meridian_deg, 49.0, 0.0});
    EXPECT_NEAR(origin.x, 500000.0, 1e-9);
    EXPECT_NEAR(origin.y, -100000.0, 1e-6);
    // The same northing differences as with the origin at the equator.
    const Vec3 p = geodetic_to_projected(tm, {-1.0, 52.0, 0.0});
    const Vec3 p0 = geodetic_to_projected(utm(32630), {-1.0, 52.0, 0.0});
    const Vec3 o0 = geodetic_to_projected(utm(32630), {tm.central_meridian_deg, 49.0, 0.0});
    EXPECT_NEAR(p.y - origin.y, p0.y - o0.y, 1e-6);
    const Geodetic back = projected_to_geodetic(tm, p.x, p.y, 0.0);
    EXPECT_NEAR(back.latitude_deg, 52.0, 1e-9);
    EXPECT_NEAR(back.longitude_deg, -1.0, 1e-9);
}

TEST(TransverseMercator, RefusesPointsOutsideTheProjection)
{
    const TransverseMercator tm = utm(32633);
    EXPECT_THROW(geodetic_to_projected(tm, {15.0, 91.0, 0.0}), InvalidInput);
    EXPECT_THROW(projected_to_geodetic(tm, 1e12, 0.0, 0.0), InvalidInput);
    EXPECT_THROW(projected_to_geodetic(tm, std::nan(""), 0.0, 0.0), InvalidInput);
}

TEST(Ecef, EquatorPoleAndHeight)
{
    const Ellipsoid e;
    const Vec3 origin = geodetic_to_ecef(e, {0.0, 0.0, 0.0});
    EXPECT_NEAR(origin.x, 6378137.0, 1e-9);
    EXPECT_NEAR(origin.y, 0.0, 1e-9);
    EXPECT_NEAR(origin.z, 0.0, 1e-9);
    const double b = e.a * (1.0 - 1.0 / e.inverse_flattening);
    const Vec3 pole = geodetic_to_ecef(e, {0.0, 90.0, 0.0});
    EXPECT_NEAR(pole.x, 0.0, 1e-6);
    EXPECT_NEAR(pole.y, 0.0, 1e-6);
    EXPECT_NEAR(pole.z, b, 1e-6);
    EXPECT_NEAR(b, 6356752.314245, 1e-6);
    const Vec3 east = geodetic_to_ecef(e, {90.0, 0.0, 10.0});
    EXPECT_NEAR(east.y, 6378147.0, 1e-9);

    // A point at height h is h along the up vector.
    const EnuFrame frame(e, {11.5, 48.1, 520.0});
    const Vec3 enu = frame.ecef_to_enu(geodetic_to_ecef(e, {11.5, 48.1, 520.0 + 123.4}));
    EXPECT_NEAR(enu.x, 0.0, 1e-6);
    EXPECT_NEAR(enu.y, 0.0, 1e-6);
    EXPECT_NEAR(enu.z, 123.4, 1e-6);
}

TEST(EnuFrame, AnchorAndHundredMetresNorth)
{
    const Ellipsoid e;
    const Geodetic anchor{10.0, 50.0, 0.0};
    const EnuFrame frame(e, anchor);
    EXPECT_EQ(frame.anchor().latitude_deg, 50.0);
    const Vec3 zero = frame.ecef_to_enu(geodetic_to_ecef(e, anchor));
    EXPECT_NEAR(norm(zero), 0.0, 1e-9);

    // Radius of curvature of the meridian: 100 m of arc is 100 / M radians of latitude.
    const double f = 1.0 / e.inverse_flattening, e2 = f * (2.0 - f);
    const double s = std::sin(radians(50.0));
    const double m = e.a * (1.0 - e2) / std::pow(1.0 - e2 * s * s, 1.5);
    const Geodetic north{10.0, 50.0 + (100.0 / m) * 180.0 / kPi, 0.0};
    const Vec3 enu = frame.ecef_to_enu(geodetic_to_ecef(e, north));
    EXPECT_NEAR(enu.x, 0.0, kMm);
    EXPECT_NEAR(enu.y, 100.0, kMm);
    EXPECT_LT(enu.z, 0.0);                              // the ellipsoid falls away below the tangent plane
    EXPECT_NEAR(enu.z, -100.0 * 100.0 / (2.0 * m), 1e-5); // by s^2 / 2M
}

TEST(EnuFrame, GridConvergenceAndScale)
{
    const TransverseMercator tm = utm(32633); // 18°E is 3° east of the central meridian
    const Geodetic g1{18.0, 45.0, 0.0};
    const Vec3 p1 = geodetic_to_projected(tm, g1);
    const Geodetic g2 = projected_to_geodetic(tm, p1.x, p1.y + 1000.0, 0.0);
    const EnuFrame frame(tm.ellipsoid, g1);
    const Vec3 d = frame.ecef_to_enu(geodetic_to_ecef(tm.ellipsoid, g2));

    // Grid north is turned east of true north by the convergence east of the central meridian.
    const double dlon = radians(3.0), phi = radians(45.0);
    const double gamma = std::atan(std::tan(dlon) * std::sin(phi)) * 180.0 / kPi;
    EXPECT_NEAR(gamma, 2.12, 0.01);
    EXPECT_NEAR(std::atan2(d.x, d.y) * 180.0 / kPi, gamma, 0.01);

    const double k = 0.9996 * (1.0 + std::pow(dlon * std::cos(phi), 2) / 2.0);
    EXPECT_NEAR(norm(d) / (1000.0 / k), 1.0, 1e-4);
}

TEST(CrsFromEpsg, Families)
{
    const auto w33 = crs_from_epsg(32633);
    ASSERT_TRUE(w33);
    EXPECT_EQ(w33->name, "WGS 84 / UTM zone 33N");
    EXPECT_EQ(w33->epsg, 32633);
    EXPECT_EQ(w33->projection.central_meridian_deg, 15.0);
    EXPECT_EQ(w33->projection.false_northing, 0.0);
    EXPECT_EQ(w33->projection.ellipsoid.inverse_flattening, 298.257223563);

    const auto w1s = crs_from_epsg(32701);
    ASSERT_TRUE(w1s);
    EXPECT_EQ(w1s->name, "WGS 84 / UTM zone 1S");
    EXPECT_EQ(w1s->projection.central_meridian_deg, -177.0);
    EXPECT_EQ(w1s->projection.false_northing, 10000000.0);
    const auto w60n = crs_from_epsg(32660);
    ASSERT_TRUE(w60n);
    EXPECT_EQ(w60n->projection.central_meridian_deg, 177.0);

    const auto nad = crs_from_epsg(26910);
    ASSERT_TRUE(nad);
    EXPECT_EQ(nad->name, "NAD83 / UTM zone 10N");
    EXPECT_EQ(nad->projection.central_meridian_deg, -123.0);
    EXPECT_EQ(nad->projection.ellipsoid.inverse_flattening, 298.257222101);
    EXPECT_TRUE(crs_from_epsg(26923));

    const auto etrs = crs_from_epsg(25832);
    ASSERT_TRUE(etrs);
    EXPECT_EQ(etrs->name, "ETRS89 / UTM zone 32N");
    EXPECT_EQ(etrs->projection.central_meridian_deg, 9.0);
    EXPECT_EQ(etrs->projection.ellipsoid.inverse_flattening, 298.257222101);
    EXPECT_TRUE(crs_from_epsg(25828));
    EXPECT_TRUE(crs_from_epsg(25838));

    const auto gda94 = crs_from_epsg(28356);
    ASSERT_TRUE(gda94);
    EXPECT_EQ(gda94->name, "GDA94 / MGA zone 56");
    EXPECT_EQ(gda94->projection.central_meridian_deg, 153.0);
    EXPECT_EQ(gda94->projection.false_northing, 10000000.0);

    const auto gda2020 = crs_from_epsg(7846);
    ASSERT_TRUE(gda2020);
    EXPECT_EQ(gda2020->name, "GDA2020 / MGA zone 46");
    EXPECT_EQ(gda2020->projection.central_meridian_deg, 93.0);
    EXPECT_EQ(gda2020->projection.false_northing, 10000000.0);
    EXPECT_EQ(gda2020->projection.scale_factor, 0.9996);
    EXPECT_EQ(gda2020->projection.false_easting, 500000.0);
    EXPECT_TRUE(crs_from_epsg(7859));

    for (const int unknown : {2264, 4326, 32600, 32661, 32700, 32761, 26900, 26924, 25827, 25839, 28347, 28359,
                              7845, 7860, 27700, 0, -32633})
        EXPECT_FALSE(crs_from_epsg(unknown)) << unknown;
}

TEST(ParseCrs, EpsgCodes)
{
    EXPECT_EQ(parse_crs("EPSG:32633").epsg, 32633);
    const ProjectedCrs etrs = parse_crs("epsg:25832");
    EXPECT_EQ(etrs.epsg, 25832);
    EXPECT_EQ(etrs.name, "ETRS89 / UTM zone 32N");
    EXPECT_EQ(parse_crs("  Epsg:7855\n").epsg, 7855);

    const std::string unsupported = parse_error("EPSG:2264");
    EXPECT_NE(unsupported.find("EPSG:2264 is not a supported projected CRS"), std::string::npos) << unsupported;
    EXPECT_NE(parse_error("32633").find("EPSG:32633"), std::string::npos);
    parse_error("EPSG:");
    parse_error("EPSG:abc");
    parse_error("EPSG:99999999999999999999");
    parse_error("");
    parse_error("   ");
}

TEST(ParseCrs, Wkt1WithAuthorityUsesTheTable)
{
    const ProjectedCrs crs = parse_crs(kWgs84Utm33);
    EXPECT_EQ(crs.epsg, 32633);
    EXPECT_EQ(crs.name, "WGS 84 / UTM zone 33N");
    expect_same_projection(crs.projection, utm(32633));
}

TEST(ParseCrs, Wkt1WithoutAuthorityReadsParameters)
{
    const ProjectedCrs crs = parse_crs(kWgs84Utm33NoId);
    EXPECT_EQ(crs.epsg, 0); // the inner AUTHORITY of the GEOGCS (4326) is not the CRS's
    EXPECT_EQ(crs.name, "WGS 84 / UTM zone 33N");
    EXPECT_EQ(crs.projection.central_meridian_deg, 15.0);
    EXPECT_EQ(crs.projection.false_easting, 500000.0);
    expect_same_projection(crs.projection, utm(32633));

    // An outer code we do not know falls back to the parameters too.
    const ProjectedCrs other = parse_crs(kWgs84Utm33Body + R"wkt(,AUTHORITY["EPSG","999999"]])wkt");
    EXPECT_EQ(other.epsg, 0);
    expect_same_projection(other.projection, utm(32633));

    // Round brackets are legal WKT delimiters as well.
    std::string round = kWgs84Utm33NoId;
    for (char& c : round)
        c = c == '[' ? '(' : c == ']' ? ')' : c;
    expect_same_projection(parse_crs(round).projection, utm(32633));
}

TEST(ParseCrs, Wkt2WithIdAndWithout)
{
    const ProjectedCrs crs = parse_crs(etrs89_utm32_wkt2(true));
    EXPECT_EQ(crs.epsg, 25832);
    EXPECT_EQ(crs.name, "ETRS89 / UTM zone 32N");

    const ProjectedCrs read = parse_crs(etrs89_utm32_wkt2(false));
    EXPECT_EQ(read.epsg, 0);
    expect_same_projection(read.projection, utm(25832));
}

TEST(ParseCrs, RefusesOtherProjectionsAndDatums)
{
    const std::string lambert =
        R"wkt(PROJCS["NAD83 / North Carolina (ftUS)",GEOGCS["NAD83",DATUM["North_American_Datum_1983",)wkt"
        R"wkt(SPHEROID["GRS 1980",6378137,298.257222101]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],)wkt"
        R"wkt(PROJECTION["Lambert_Conformal_Conic_2SP"],PARAMETER["standard_parallel_1",36.16666666666666],)wkt"
        R"wkt(PARAMETER["standard_parallel_2",34.33333333333334],PARAMETER["latitude_of_origin",33.75],)wkt"
        R"wkt(PARAMETER["central_meridian",-79],PARAMETER["false_easting",2000000.002616666],)wkt"
        R"wkt(PARAMETER["false_northing",0],UNIT["US survey foot",0.3048006096012192],AUTHORITY["EPSG","2264"]])wkt";
    const std::string lambert_error = parse_error(lambert);
    EXPECT_NE(lambert_error.find("Lambert_Conformal_Conic_2SP"), std::string::npos) << lambert_error;

    const std::string osgb =
        R"wkt(PROJCS["OSGB 1936 / British National Grid",GEOGCS["OSGB 1936",DATUM["OSGB_1936",)wkt"
        R"wkt(SPHEROID["Airy 1830",6377563.396,299.3249646,AUTHORITY["EPSG","7001"]],)wkt"
        R"wkt(TOWGS84[446.448,-125.157,542.06,0.15,0.247,0.842,-20.489],AUTHORITY["EPSG","6277"]],)wkt"
        R"wkt(PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4277"]],)wkt"
        R"wkt(PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",49],)wkt"
        R"wkt(PARAMETER["central_meridian",-2],)wkt"
        R"wkt(PARAMETER["scale_factor",0.9996012717],PARAMETER["false_easting",400000],)wkt"
        R"wkt(PARAMETER["false_northing",-100000],UNIT["metre",1],AXIS["Easting",EAST],AXIS["Northing",NORTH],)wkt"
        R"wkt(AUTHORITY["EPSG","27700"]])wkt";
    const std::string osgb_error = parse_error(osgb);
    EXPECT_NE(osgb_error.find("datum \"OSGB_1936\" is not supported"), std::string::npos) << osgb_error;
    EXPECT_NE(osgb_error.find("--enu"), std::string::npos) << osgb_error;

    const std::string geographic =
        R"wkt(GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],)wkt"
        R"wkt(UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]])wkt";
    EXPECT_NE(parse_error(geographic).find("geographic CRS \"WGS 84\""), std::string::npos);
    const std::string geocentric =
        R"wkt(GEOCCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],)wkt"
        R"wkt(UNIT["metre",1]])wkt";
    EXPECT_NE(parse_error(geocentric).find("geocentric"), std::string::npos);
}

TEST(ParseCrs, UsFeetUnit)
{
    const std::string feet =
        R"wkt(PROJCS["NAD83 / UTM zone 17N (ftUS)",GEOGCS["NAD83",DATUM["North_American_Datum_1983",)wkt"
        R"wkt(SPHEROID["GRS 1980",6378137,298.257222101]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],)wkt"
        R"wkt(PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],)wkt"
        R"wkt(PARAMETER["central_meridian",-81],)wkt"
        R"wkt(PARAMETER["scale_factor",0.9996],PARAMETER["false_easting",1640416.666666667],)wkt"
        R"wkt(PARAMETER["false_northing",0],UNIT["US survey foot",0.3048006096012192],AXIS["Easting",EAST],)wkt"
        R"wkt(AXIS["Northing",NORTH]])wkt";
    const ProjectedCrs crs = parse_crs(feet);
    EXPECT_EQ(crs.epsg, 0);
    EXPECT_DOUBLE_EQ(crs.projection.unit_to_metre, 0.3048006096012192);
    EXPECT_EQ(crs.projection.central_meridian_deg, -81.0);

    // The same place as in metres (NAD83 / UTM zone 17N), heights converted too.
    const TransverseMercator metres = utm(26917);
    const Geodetic g{-80.2, 35.5, 30.48006096012192};
    const Vec3 ft = geodetic_to_projected(crs.projection, g);
    const Vec3 m = geodetic_to_projected(metres, g);
    EXPECT_NEAR(ft.x * 0.3048006096012192, m.x, kMm);
    EXPECT_NEAR(ft.y * 0.3048006096012192, m.y, kMm);
    EXPECT_NEAR(ft.z, 100.0, 1e-9);
    const Geodetic back = projected_to_geodetic(crs.projection, ft.x, ft.y, 100.0);
    EXPECT_NEAR(back.height, 30.48006096012192, 1e-9);
    EXPECT_NEAR(back.latitude_deg, 35.5, 1e-9);
}

TEST(ParseCrs, CompoundCrs)
{
    const std::string metre_height =
        R"wkt(COMPD_CS["WGS 84 / UTM zone 33N + EGM96 height",)wkt" + kWgs84Utm33 +
        R"wkt(,VERT_CS["EGM96 height",VERT_DATUM["EGM96 geoid",2005],UNIT["metre",1],AXIS["Up",UP]]])wkt";
    EXPECT_EQ(parse_crs(metre_height).epsg, 32633);
    const std::string foot_height =
        R"wkt(COMPD_CS["WGS 84 / UTM zone 33N + height in feet",)wkt" + kWgs84Utm33 +
        R"wkt(,VERT_CS["height (ft)",VERT_DATUM["EGM96 geoid",2005],UNIT["foot",0.3048],AXIS["Up",UP]]])wkt";
    EXPECT_NE(parse_error(foot_height).find("vertical"), std::string::npos);
}

TEST(ParseCrs, MalformedWktThrows)
{
    parse_error("PROJCS[");
    parse_error(R"wkt(PROJCS["x")wkt");
    parse_error(R"wkt(PROJCS["x"]])wkt");
    parse_error(R"wkt(PROJCS["x"))wkt");         // mismatched delimiters
    parse_error(R"wkt(PROJCS["x" 5])wkt");       // missing comma
    parse_error(R"wkt(PROJCS["unterminated)wkt"); // unterminated quote
    parse_error(R"wkt(PROJCS["a"", b])wkt");     // "" escape then unterminated
    parse_error("PROJCS[]");
    parse_error("PROJCS[#]");
    parse_error(R"wkt(PROJCS["x",PROJECTION["Transverse_Mercator"]])wkt"); // no datum
    parse_error(R"wkt(PROJCS["x",GEOGCS["g",DATUM["WGS_1984"]],PROJECTION["Transverse_Mercator"]])wkt"); // no spheroid

    std::string deep;
    for (int i = 0; i < 10000; ++i)
        deep += "PROJCS[";
    parse_error(deep);
    for (int i = 0; i < 10000; ++i)
        deep += "]";
    EXPECT_NE(parse_error(deep).find("nested deeper"), std::string::npos);

    // Every truncation of a valid WKT is refused cleanly.
    for (std::size_t n = 1; n < kWgs84Utm33.size(); ++n)
        parse_error(kWgs84Utm33.substr(0, n));

    // Text quoted from the input stays on one line: a .prj file of two lines of words, a name broken
    // across lines (QA round 29: the error took two lines).
    for (const std::string& text : {std::string("hello\nworld\n"), std::string("EPSG:32\n633"),
                                    std::string("PROJCS[\"bad\nname\",PROJECTION[\"Transverse_Mercator\"]]")}) {
        const std::string error = parse_error(text);
        EXPECT_EQ(error.find('\n'), std::string::npos) << error;
    }
    EXPECT_NE(parse_error("hello\nworld").find("\"hello world\""), std::string::npos);
}

// QA round qa-fuzz: text of the input was quoted whole in messages, so that a .prj or a LAS file's WKT
// record with a name, a keyword or an EPSG "code" of a megabyte gave a one-line error of a megabyte (and
// a CRS name of that size was printed wherever the CRS is named). Quoted input is cut to 80 characters.
TEST(ParseCrs, LongInputIsShortenedInMessages)
{
    const std::string longest(1 << 20, 'N');
    const auto renamed = [&](const std::string& wkt) {
        std::string out = wkt;
        out.replace(out.find("WGS 84 / UTM zone 33N"), 21, longest);
        return out;
    };
    std::string unsupported = renamed(kWgs84Utm33NoId);
    unsupported.replace(unsupported.find("Transverse_Mercator"), 19, "Mercator_1SP");
    std::string bad_scale = renamed(kWgs84Utm33NoId);
    bad_scale.replace(bad_scale.find("0.9996"), 6, "-0.9996");
    std::string bad_unit = kWgs84Utm33NoId;
    bad_unit.replace(bad_unit.find("UNIT[\"metre\",1"), 14, "UNIT[\"" + longest + "\",0");
    for (const std::string& text :
         {unsupported, bad_scale, "EPSG:" + longest, longest + "[%]", longest + "[1]", "PROJCS[\"" + longest + "\"]",
          "PROJCS[\"x\"," + longest + "[%]]", "COMPD_CS[\"" + longest + "\"]", bad_unit}) {
        const std::string error = parse_error(text);
        EXPECT_LT(error.size(), 400u) << error.substr(0, 200);
        EXPECT_NE(error.find("..."), std::string::npos) << error.substr(0, 200);
    }
    // A CRS it can place keeps a name of at most 80 characters; short names are kept whole.
    const ProjectedCrs named = parse_crs(renamed(kWgs84Utm33NoId));
    EXPECT_EQ(named.name, std::string(77, 'N') + "...");
    EXPECT_EQ(parse_crs(kWgs84Utm33NoId).name, "WGS 84 / UTM zone 33N");
    EXPECT_LE(crs_label(renamed(kWgs84Utm33NoId)).size(), 80u);
    EXPECT_LE(crs_label("EPSG:" + std::string(1000, ' ') + "32633").size(), 80u);
    // Cut between UTF-8 characters, never inside one (the name stays valid UTF-8).
    std::string accented = kWgs84Utm33NoId;
    std::string umlauts;
    for (int i = 0; i < 100; ++i)
        umlauts += "\xC3\xA4"; // ä
    accented.replace(accented.find("WGS 84 / UTM zone 33N"), 21, "xy" + umlauts);
    EXPECT_EQ(parse_crs(accented).name, "xy" + umlauts.substr(0, 74) + "..."); // 77 bytes would split an ä
}

// QA round qa-left: files in EPSG:32633 and in the WKT of another system merged without a word (only two
// EPSG codes were compared). crs_differ tells systems apart by code, else by projection, ellipsoid and
// unit; two spellings of one system, or systems it cannot read, never differ.
TEST(CrsDiffer, CodesWktAndUnreadableSystems)
{
    const std::string utm32_no_id = [] {
        std::string wkt = kWgs84Utm33NoId;
        wkt.replace(wkt.find("zone 33N"), 8, "zone 32N");
        wkt.replace(wkt.find("\"central_meridian\",15"), 21, "\"central_meridian\",9");
        return wkt;
    }();
    // One system, spelled as a code, as WKT with its id, as WKT without it, in WKT2.
    for (const std::string& same : {std::string("EPSG:32633"), std::string("epsg: 32633"), kWgs84Utm33, kWgs84Utm33NoId})
        for (const std::string& other : {std::string("EPSG:32633"), kWgs84Utm33, kWgs84Utm33NoId}) {
            EXPECT_FALSE(crs_differ(same, other)) << same << " | " << other;
            EXPECT_FALSE(crs_differ(other, same)) << same << " | " << other;
        }
    EXPECT_FALSE(crs_differ("EPSG:25832", etrs89_utm32_wkt2(false)));
    EXPECT_FALSE(crs_differ(etrs89_utm32_wkt2(true), etrs89_utm32_wkt2(false)));
    // Another zone, another ellipsoid (WGS 84 vs GRS80 in the same zone), another code.
    EXPECT_TRUE(crs_differ("EPSG:32632", kWgs84Utm33NoId));
    EXPECT_TRUE(crs_differ(kWgs84Utm33NoId, utm32_no_id));
    EXPECT_FALSE(crs_differ("EPSG:32632", utm32_no_id));
    EXPECT_TRUE(crs_differ("EPSG:32632", etrs89_utm32_wkt2(false)));
    EXPECT_TRUE(crs_differ(kWgs84Utm33, etrs89_utm32_wkt2(true)));
    EXPECT_TRUE(crs_differ("EPSG:2264", "EPSG:2263")); // codes compare even when unsupported
    // What parse_crs cannot read is not compared beyond its code: a Lambert WKT, a geographic code.
    const std::string lambert = R"wkt(PROJCS["x",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]]],)wkt"
                                R"wkt(PROJECTION["Lambert_Conformal_Conic_2SP"]])wkt";
    EXPECT_FALSE(crs_differ(lambert, "EPSG:32633"));
    EXPECT_FALSE(crs_differ("EPSG:4326", kWgs84Utm33NoId));
    // Labels for messages: codes as written, WKT by name and code, one line.
    EXPECT_EQ(crs_label("EPSG:32632"), "EPSG:32632");
    EXPECT_EQ(crs_label(kWgs84Utm33), "WGS 84 / UTM zone 33N (EPSG:32633)");
    EXPECT_EQ(crs_label(kWgs84Utm33NoId), "WGS 84 / UTM zone 33N");
    EXPECT_EQ(crs_label("PROJCS[\"a\nb\"," + std::string(100, 'x')).find('\n'), std::string::npos);
    EXPECT_EQ(crs_label("PROJCS[\"a\nb\"," + std::string(100, 'x')).size(), 60u);
}

} // namespace
} // namespace mrt
