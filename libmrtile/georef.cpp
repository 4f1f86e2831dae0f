// Georeferencing without PROJ: input clouds come in a projected CRS (almost always UTM or a sibling
// such as MGA), 3D Tiles wants Earth-centred coordinates. Transverse Mercator is inverted with the
// Krüger series to sixth order (Karney 2011, "Transverse Mercator with an accuracy of a few
// nanometers"), the conformal latitude by Newton's method; the CRS comes from a small EPSG table or
// from the Transverse Mercator parameters of a WKT1/WKT2 string, read by a small bracket-tree parser
// that refuses (never crashes on) anything it does not understand.
#include "libmrtile/georef.h"

#include "libmrtile/errors.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <vector>

namespace mrt {
namespace {

constexpr double kDegree = kPi / 180.0;

std::string format_number(double x)
{
    std::ostringstream s;
    s.precision(12);
    s << x;
    return s.str();
}

// Longitude difference into [-180, 180]: remainder is exact, so whole-degree meridians stay whole.
double wrap_degrees(double degrees) { return std::remainder(degrees, 360.0); }

// ---------------------------------------------------------------------------------------------------
// Transverse Mercator

// The ellipsoid-dependent constants of the Krüger series: the rectifying radius A (2πA is a meridian's
// length) and the coefficients alpha (conformal sphere → projection) and beta (back), to n^6.
struct Series
{
    double e = 0;   // eccentricity
    double e2m = 1; // 1 - e^2
    double A = 0;
    std::array<double, 6> alpha{}, beta{};
};

double flattening(const Ellipsoid& e)
{
    if (!(std::isfinite(e.a) && e.a > 0.0) ||
        !(e.inverse_flattening == 0.0 || (std::isfinite(e.inverse_flattening) && e.inverse_flattening > 1.0)))
        throw InvalidInput("ellipsoid: the semi-major axis must be > 0 and the inverse flattening > 1 (or 0 for "
                           "a sphere), got a " + format_number(e.a) + ", 1/f " + format_number(e.inverse_flattening));
    return e.inverse_flattening == 0.0 ? 0.0 : 1.0 / e.inverse_flattening;
}

Series make_series(const Ellipsoid& ellipsoid)
{
    const double f = flattening(ellipsoid);
    const double n = f / (2.0 - f);
    const double n2 = n * n, n3 = n2 * n, n4 = n3 * n, n5 = n4 * n, n6 = n5 * n;
    Series s;
    s.e2m = 1.0 - f * (2.0 - f);
    s.e = std::sqrt(f * (2.0 - f));
    s.A = ellipsoid.a / (1.0 + n) * (1.0 + n2 / 4.0 + n4 / 64.0 + n6 / 256.0);
    s.alpha = {n / 2 - 2 * n2 / 3 + 5 * n3 / 16 + 41 * n4 / 180 - 127 * n5 / 288 + 7891 * n6 / 37800,
               13 * n2 / 48 - 3 * n3 / 5 + 557 * n4 / 1440 + 281 * n5 / 630 - 1983433 * n6 / 1935360,
               61 * n3 / 240 - 103 * n4 / 140 + 15061 * n5 / 26880 + 167603 * n6 / 181440,
               49561 * n4 / 161280 - 179 * n5 / 168 + 6601661 * n6 / 7257600,
               34729 * n5 / 80640 - 3418889 * n6 / 1995840,
               212378941 * n6 / 319334400};
    s.beta = {n / 2 - 2 * n2 / 3 + 37 * n3 / 96 - n4 / 360 - 81 * n5 / 512 + 96199 * n6 / 604800,
              n2 / 48 + n3 / 15 - 437 * n4 / 1440 + 46 * n5 / 105 - 1118711 * n6 / 3870720,
              17 * n3 / 480 - 37 * n4 / 840 - 209 * n5 / 4480 + 5569 * n6 / 90720,
              4397 * n4 / 161280 - 11 * n5 / 504 - 830251 * n6 / 7257600,
              4583 * n5 / 161280 - 108847 * n6 / 3991680,
              20648693 * n6 / 638668800};
    return s;
}

double eatanhe(const Series& s, double x) { return s.e > 0.0 ? s.e * std::atanh(s.e * x) : 0.0; }

// tan of the conformal latitude from tan of the geodetic latitude. Working with tangents rather than
// angles keeps full relative precision up to the poles (tan(pi/2) is finite in doubles).
double taupf(const Series& s, double tau)
{
    const double tau1 = std::hypot(1.0, tau);
    const double sig = std::sinh(eatanhe(s, tau / tau1));
    return std::hypot(1.0, sig) * tau - sig * tau1;
}

// The inverse of taupf by Newton's method (Karney 2011, eq. 19-21): two or three steps reach machine
// precision; the bound only guards against a non-converging input such as NaN.
double tauf(const Series& s, double taup)
{
    if (s.e == 0.0)
        return taup;
    const double tol = 0.1 * std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::fabs(taup));
    double tau = std::fabs(taup) > 70.0 ? taup * std::exp(eatanhe(s, 1.0)) : taup / s.e2m;
    for (int i = 0; i < 10; ++i) {
        const double taupa = taupf(s, tau);
        const double dtau = (taup - taupa) * (1.0 + s.e2m * tau * tau) /
                            (s.e2m * std::hypot(1.0, tau) * std::hypot(1.0, taupa));
        tau += dtau;
        if (!(std::fabs(dtau) >= tol))
            break;
    }
    return tau;
}

// (xi', eta') on the conformal sphere → (xi, eta) of the projection, both in units of A.
void krueger_forward(const Series& s, double xip, double etap, double& xi, double& eta)
{
    xi = xip;
    eta = etap;
    for (int j = 1; j <= 6; ++j) {
        const double k = 2.0 * j;
        xi += s.alpha[j - 1] * std::sin(k * xip) * std::cosh(k * etap);
        eta += s.alpha[j - 1] * std::cos(k * xip) * std::sinh(k * etap);
    }
}

// Meridian distance from the equator to the latitude of origin, which a non-zero origin subtracts
// from every northing.
double origin_northing(const Series& s, double latitude_of_origin_deg)
{
    if (latitude_of_origin_deg == 0.0)
        return 0.0;
    const double xip = std::atan(taupf(s, std::tan(latitude_of_origin_deg * kDegree)));
    double xi = 0, eta = 0;
    krueger_forward(s, xip, 0.0, xi, eta);
    return s.A * xi;
}

void check_projection(const TransverseMercator& tm, const char* where)
{
    if (!(std::isfinite(tm.central_meridian_deg) && std::isfinite(tm.latitude_of_origin_deg) &&
          std::fabs(tm.latitude_of_origin_deg) <= 90.0 && std::isfinite(tm.scale_factor) && tm.scale_factor > 0.0 &&
          std::isfinite(tm.false_easting) && std::isfinite(tm.false_northing) && std::isfinite(tm.unit_to_metre) &&
          tm.unit_to_metre > 0.0))
        throw InvalidInput(std::string(where) + ": the Transverse Mercator needs finite parameters, a latitude of "
                           "origin within [-90, 90], a scale factor > 0 and a unit > 0 m");
}

void check_geodetic(const Geodetic& g, const char* where)
{
    if (!(std::isfinite(g.longitude_deg) && std::isfinite(g.latitude_deg) && std::isfinite(g.height) &&
          std::fabs(g.latitude_deg) <= 90.0))
        throw InvalidInput(std::string(where) + ": longitude, latitude and height must be finite and the latitude "
                           "within [-90, 90], got (" + format_number(g.longitude_deg) + ", " +
                           format_number(g.latitude_deg) + ", " + format_number(g.height) + ")");
}

// ---------------------------------------------------------------------------------------------------
// WKT: a tree of KEYWORD[value, ...] nodes; values are quoted strings, numbers, bare words (AXIS
// directions) or nested nodes. Only what placement needs is read from it.

struct WktAtom
{
    std::string text;
    bool quoted = false;
};

struct WktNode
{
    std::string keyword; // upper case
    std::vector<WktAtom> atoms;
    std::vector<WktNode> children;
};

// Input text as a message quotes it (defined below, with one_line).
std::string shown(const std::string& text, std::size_t max = 80);

class WktParser
{
public:
    explicit WktParser(const std::string& text) : s_(text) {}

    WktNode parse()
    {
        skip_space();
        WktNode root = node(0);
        skip_space();
        if (pos_ != s_.size())
            fail("unexpected text after the closing bracket of " + shown(root.keyword));
        return root;
    }

private:
    // Real CRS definitions nest about 6 deep; the bound keeps hostile input from exhausting the stack.
    static constexpr int kMaxDepth = 32;

    [[noreturn]] void fail(const std::string& what) const
    {
        throw InvalidInput("malformed WKT at character " + std::to_string(pos_ + 1) + ": " + what);
    }

    void skip_space()
    {
        while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_])))
            ++pos_;
    }

    static bool is_word_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
    static bool is_word_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

    std::string word()
    {
        const std::size_t start = pos_;
        while (pos_ < s_.size() && is_word_char(s_[pos_]))
            ++pos_;
        return s_.substr(start, pos_ - start);
    }

    std::string quoted()
    {
        ++pos_; // opening quote
        std::string out;
        for (;;) {
            if (pos_ >= s_.size())
                fail("unterminated quoted string");
            const char c = s_[pos_++];
            if (c != '"')
                out += c;
            else if (pos_ < s_.size() && s_[pos_] == '"') { // "" stands for one quote
                out += '"';
                ++pos_;
            } else
                return out;
        }
    }

    std::string number()
    {
        const std::size_t start = pos_;
        while (pos_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '.' ||
                                    s_[pos_] == '+' || s_[pos_] == '-' || s_[pos_] == 'e' || s_[pos_] == 'E'))
            ++pos_;
        return s_.substr(start, pos_ - start);
    }

    WktNode node(int depth)
    {
        if (pos_ >= s_.size() || !is_word_start(s_[pos_]))
            fail("expected a keyword such as PROJCS or PROJCRS");
        WktNode n;
        n.keyword = word();
        std::transform(n.keyword.begin(), n.keyword.end(), n.keyword.begin(),
                       [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
        return body(std::move(n), depth);
    }

    WktNode body(WktNode n, int depth)
    {
        if (depth >= kMaxDepth)
            fail("brackets nested deeper than " + std::to_string(kMaxDepth) + " levels");
        skip_space();
        if (pos_ >= s_.size() || (s_[pos_] != '[' && s_[pos_] != '('))
            fail("expected '[' after " + shown(n.keyword));
        const char close = s_[pos_++] == '[' ? ']' : ')';
        skip_space();
        if (pos_ < s_.size() && s_[pos_] == close) {
            ++pos_;
            return n;
        }
        for (;;) {
            skip_space();
            if (pos_ >= s_.size())
                fail("unbalanced brackets: " + shown(n.keyword) + " is not closed");
            const char c = s_[pos_];
            if (c == '"')
                n.atoms.push_back({quoted(), true});
            else if (is_word_start(c)) {
                WktNode child;
                child.keyword = word();
                skip_space();
                if (pos_ < s_.size() && (s_[pos_] == '[' || s_[pos_] == '(')) {
                    std::transform(child.keyword.begin(), child.keyword.end(), child.keyword.begin(),
                                   [](unsigned char ch) { return static_cast<char>(std::toupper(ch)); });
                    n.children.push_back(body(std::move(child), depth + 1));
                } else
                    n.atoms.push_back({child.keyword, false});
            } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.')
                n.atoms.push_back({number(), false});
            else
                fail(std::string("unexpected character '") + c + "' in " + shown(n.keyword));
            skip_space();
            if (pos_ >= s_.size())
                fail("unbalanced brackets: " + shown(n.keyword) + " is not closed");
            if (s_[pos_] == ',') {
                ++pos_;
                continue;
            }
            if (s_[pos_] == close) {
                ++pos_;
                return n;
            }
            fail(std::string("expected ',' or '") + close + "' in " + shown(n.keyword));
        }
    }

    const std::string& s_;
    std::size_t pos_ = 0;
};

// Lower case with '_' as ' ', so that "WGS_1984" (WKT1) and "WGS 1984" compare equal.
std::string normalized_name(const std::string& name)
{
    std::string out;
    out.reserve(name.size());
    for (const char c : name)
        out += c == '_' ? ' ' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

bool has_keyword(const WktNode& n, std::initializer_list<const char*> keywords)
{
    for (const char* k : keywords)
        if (n.keyword == k)
            return true;
    return false;
}

const WktNode* first_child(const WktNode& n, std::initializer_list<const char*> keywords)
{
    for (const WktNode& c : n.children)
        if (has_keyword(c, keywords))
            return &c;
    return nullptr;
}

// First descendant in pre-order (the tree is at most kMaxDepth deep, so recursion is bounded).
const WktNode* find_descendant(const WktNode& n, std::initializer_list<const char*> keywords)
{
    for (const WktNode& c : n.children) {
        if (has_keyword(c, keywords))
            return &c;
        if (const WktNode* d = find_descendant(c, keywords))
            return d;
    }
    return nullptr;
}

// Text of the input shown in a message or printed as a name: on one line, control characters (the line
// breaks of a .prj file, a name split across lines) as blanks. An error quoting "hello\nworld" from a
// .prj file took two lines (QA round 29), and errors are one line.
std::string one_line(std::string text)
{
    std::replace_if(text.begin(), text.end(), [](char c) { return std::iscntrl(static_cast<unsigned char>(c)) != 0; }, ' ');
    return text;
}

// Input text quoted in a message or kept as a CRS's name: on one line, and cut to `max` characters (at
// a UTF-8 character's start). A WKT name, keyword or EPSG "code" of a megabyte was quoted whole: a
// one-line error of a megabyte (QA round qa-fuzz).
std::string shown(const std::string& text, std::size_t max)
{
    if (text.size() <= max)
        return one_line(text);
    std::size_t cut = max - 3;
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) // a UTF-8 continuation byte
        --cut;
    return one_line(text.substr(0, cut)) + "...";
}

// The name of a node (its first quoted value), whole: for comparisons; messages quote it through shown.
std::string name_of(const WktNode& n)
{
    for (const WktAtom& a : n.atoms)
        if (a.quoted)
            return one_line(a.text);
    return {};
}

bool parse_double(const std::string& text, double& out)
{
    const char* first = text.data();
    const char* last = first + text.size();
    if (first != last && *first == '+') // from_chars takes no '+'
        ++first;
    const auto [ptr, ec] = std::from_chars(first, last, out);
    return ec == std::errc() && ptr == last && std::isfinite(out);
}

// The index-th number (unquoted value) of a node, e.g. SPHEROID["WGS 84",6378137,298.257223563] → 1
// gives the inverse flattening.
double number_of(const WktNode& n, std::size_t index)
{
    std::size_t seen = 0;
    for (const WktAtom& a : n.atoms) {
        if (a.quoted)
            continue;
        double x = 0;
        if (parse_double(a.text, x) && seen++ == index)
            return x;
    }
    throw InvalidInput("WKT " + shown(n.keyword) + "[\"" + shown(name_of(n)) + "\"...] lacks a number it needs");
}

// The conversion factor of a unit node (UNIT["US survey foot",0.3048006096012192]), checked positive.
double unit_factor(const WktNode& unit)
{
    const double f = number_of(unit, 0);
    if (!(f > 0.0))
        throw InvalidInput("WKT " + shown(unit.keyword) + "[\"" + shown(name_of(unit)) + "\"," + format_number(f) +
                           "] must have a conversion factor > 0");
    return f;
}

// An integer code such as "32633" (WKT1 quotes it) or 32633 (WKT2 does not); -1 if it is not one.
int parse_code(const std::string& text)
{
    if (text.empty() || text.size() > 9 ||
        !std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
        return -1;
    return std::stoi(text);
}

// The EPSG code of the CRS node itself: its last AUTHORITY (WKT1) or ID (WKT2) child naming EPSG.
int epsg_code_of(const WktNode& crs)
{
    int code = -1;
    for (const WktNode& c : crs.children)
        if (has_keyword(c, {"AUTHORITY", "ID"}) && c.atoms.size() >= 2 && normalized_name(c.atoms[0].text) == "epsg")
            code = parse_code(c.atoms[1].text);
    return code;
}

// WKT names (normalized) of WGS 84 and the datums within about 2 m of it, in EPSG, OGC WKT1 and ESRI
// spellings ("D_North_American_1983", "D_ETRS_1989").
bool is_supported_datum(const std::string& name)
{
    const std::string n = normalized_name(name);
    for (const char* known : {"wgs 1984", "wgs 84", "wgs84", "world geodetic system 1984", "north american datum 1983",
                              "north american 1983", "nad83", "european terrestrial reference", "etrs89", "etrs 1989",
                              "gda94", "gda 1994", "gda2020", "gda 2020", "geocentric datum of australia"})
        if (n.find(known) != std::string::npos)
            return true;
    return false;
}

// An angle in degrees from a value in a unit of `radians_per_unit`. WKT writes the degree as
// 0.0174532925199433 (rounded), which would turn a central meridian of 15 into 15.000000000000002: a
// factor that rounds to the degree is taken as exactly the degree.
double to_degrees(double value, double radians_per_unit)
{
    return std::fabs(radians_per_unit / kDegree - 1.0) < 1e-12 ? value : value * radians_per_unit / kDegree;
}

const char* const kOnlyTm = "only Transverse Mercator projections (UTM, MGA and similar) on WGS 84, NAD83, ETRS89, "
                            "GDA94 or GDA2020 are supported; place the tileset with --enu";

// The length unit of a CRS node in metres: its own UNIT/LENGTHUNIT child, else that of its first AXIS
// (WKT2 may give the unit per axis); 0 if it names none.
double length_unit_of(const WktNode& crs)
{
    if (const WktNode* u = first_child(crs, {"UNIT", "LENGTHUNIT"}))
        return unit_factor(*u);
    if (const WktNode* axis = first_child(crs, {"AXIS"}))
        if (const WktNode* u = first_child(*axis, {"UNIT", "LENGTHUNIT"}))
            return unit_factor(*u);
    return 0.0;
}

ProjectedCrs projected_from_wkt(const WktNode& crs)
{
    // An EPSG code we know beats reading parameters: the table is exact, the WKT may be rounded.
    const int code = epsg_code_of(crs);
    if (code > 0)
        if (std::optional<ProjectedCrs> known = crs_from_epsg(code))
            return *known;

    const bool wkt1 = crs.keyword == "PROJCS";
    const std::string crs_name = shown(name_of(crs)); // ProjectedCrs::name, and quoted in messages
    const WktNode* conversion = wkt1 ? &crs : first_child(crs, {"CONVERSION"});
    const WktNode* method = conversion ? first_child(*conversion, {"PROJECTION", "METHOD"}) : nullptr;
    if (!method)
        throw InvalidInput("projected CRS \"" + crs_name + "\" names no projection method in its WKT; " + kOnlyTm);
    if (normalized_name(name_of(*method)) != "transverse mercator")
        throw InvalidInput("projection \"" + shown(name_of(*method)) + "\" of \"" + crs_name + "\" is not supported: " +
                           kOnlyTm);

    const WktNode* datum = find_descendant(crs, {"DATUM", "GEODETICDATUM", "TRF", "ENSEMBLE"});
    if (!datum)
        throw InvalidInput("projected CRS \"" + crs_name + "\" names no datum in its WKT; " + kOnlyTm);
    if (!is_supported_datum(name_of(*datum)))
        throw InvalidInput("datum \"" + shown(name_of(*datum)) + "\" is not supported: only WGS 84 and datums within ~2 m "
                           "of it (NAD83, ETRS89, GDA94, GDA2020); place the tileset with --enu");

    ProjectedCrs out;
    out.name = crs_name;
    TransverseMercator& tm = out.projection;
    const WktNode* ellipsoid = find_descendant(crs, {"SPHEROID", "ELLIPSOID"});
    if (!ellipsoid)
        throw InvalidInput("projected CRS \"" + crs_name + "\" names no SPHEROID/ELLIPSOID in its WKT");
    const WktNode* axis_unit = first_child(*ellipsoid, {"LENGTHUNIT", "UNIT"}); // WKT2 only; WKT1 is in metres
    tm.ellipsoid.a = number_of(*ellipsoid, 0) * (axis_unit ? unit_factor(*axis_unit) : 1.0);
    tm.ellipsoid.inverse_flattening = number_of(*ellipsoid, 1);
    flattening(tm.ellipsoid); // throws on a nonsensical ellipsoid

    const double linear = length_unit_of(crs);
    tm.unit_to_metre = linear > 0.0 ? linear : 1.0;

    // Angles without a unit of their own are in the geographic CRS's unit (WKT1 always; degrees unless
    // it says otherwise, e.g. grads in French WKT).
    const WktNode* geographic = first_child(crs, {"GEOGCS", "BASEGEOGCRS", "BASEGEODCRS"});
    double angle = kDegree; // radians per unit
    if (geographic)
        if (const WktNode* u = first_child(*geographic, {"UNIT", "ANGLEUNIT"}))
            angle = unit_factor(*u);
    double prime_meridian_deg = 0.0;
    if (geographic)
        if (const WktNode* pm = find_descendant(*geographic, {"PRIMEM", "PRIMEMERIDIAN"})) {
            const WktNode* u = first_child(*pm, {"UNIT", "ANGLEUNIT"});
            prime_meridian_deg = to_degrees(number_of(*pm, 0), u ? unit_factor(*u) : angle);
        }

    tm.scale_factor = 1.0; // OGC defaults for parameters a WKT leaves out
    tm.false_easting = 0.0;
    tm.central_meridian_deg = 0.0;
    for (const WktNode& p : conversion->children) {
        if (p.keyword != "PARAMETER")
            continue;
        const std::string name = normalized_name(name_of(p));
        const double value = number_of(p, 0);
        const WktNode* u = first_child(p, {"UNIT", "ANGLEUNIT", "LENGTHUNIT", "SCALEUNIT"});
        const double factor = u ? unit_factor(*u) : 0.0;
        if (name == "latitude of origin" || name == "latitude of natural origin")
            tm.latitude_of_origin_deg = to_degrees(value, u ? factor : angle);
        else if (name == "central meridian" || name == "longitude of natural origin")
            tm.central_meridian_deg = to_degrees(value, u ? factor : angle);
        else if (name == "scale factor" || name == "scale factor at natural origin")
            tm.scale_factor = value * (u ? factor : 1.0);
        else if (name == "false easting")
            tm.false_easting = u ? value * factor / tm.unit_to_metre : value;
        else if (name == "false northing")
            tm.false_northing = u ? value * factor / tm.unit_to_metre : value;
    }
    tm.central_meridian_deg = wrap_degrees(tm.central_meridian_deg + prime_meridian_deg);
    check_projection(tm, ("projected CRS \"" + crs_name + "\"").c_str());
    return out;
}

bool is_projected(const WktNode& n) { return has_keyword(n, {"PROJCS", "PROJCRS", "PROJECTEDCRS"}); }

[[noreturn]] void refuse_kind(const WktNode& n)
{
    const std::string what = "\"" + shown(name_of(n)) + "\" (" + shown(n.keyword) + ")";
    if (has_keyword(n, {"GEOGCS", "GEOGCRS", "GEOGRAPHICCRS"}))
        throw InvalidInput("geographic CRS " + what + " is not supported: coordinates must be projected; " + kOnlyTm);
    if (has_keyword(n, {"GEOCCS", "GEODCRS", "GEODETICCRS"}))
        throw InvalidInput("geocentric/geodetic CRS " + what + " is not supported; " + kOnlyTm);
    throw InvalidInput("CRS " + what + " is not a supported projected CRS; " + kOnlyTm);
}

ProjectedCrs parse_wkt(const std::string& text)
{
    const WktNode root = WktParser(text).parse();
    const WktNode* crs = &root;
    const WktNode* vertical = nullptr;
    // A bound CRS carries its source CRS plus a transformation we ignore (see the header on datums).
    if (crs->keyword == "BOUNDCRS") {
        const WktNode* source = first_child(*crs, {"SOURCECRS"});
        if (!source || source->children.empty())
            throw InvalidInput("WKT BOUNDCRS has no SOURCECRS");
        crs = &source->children.front();
    }
    // LAS files often carry the horizontal and the vertical CRS together.
    if (has_keyword(*crs, {"COMPD_CS", "COMPOUNDCRS"})) {
        const WktNode* compound = crs;
        vertical = first_child(*compound, {"VERT_CS", "VERTCRS", "VERTICALCRS"});
        crs = first_child(*compound, {"PROJCS", "PROJCRS", "PROJECTEDCRS"});
        if (!crs) {
            for (const WktNode& c : compound->children)
                if (!has_keyword(c, {"VERT_CS", "VERTCRS", "VERTICALCRS", "AUTHORITY", "ID", "USAGE", "REMARK"}))
                    refuse_kind(c);
            throw InvalidInput("compound CRS \"" + shown(name_of(*compound)) + "\" has no projected part; " + kOnlyTm);
        }
    }
    if (!is_projected(*crs))
        refuse_kind(*crs);
    ProjectedCrs out = projected_from_wkt(*crs);
    // One unit serves horizontal and vertical coordinates, so a vertical CRS in another unit (metres over
    // a feet grid) would scale heights wrongly.
    if (vertical) {
        const double v = length_unit_of(*vertical);
        if (v > 0.0 && std::fabs(v - out.projection.unit_to_metre) > 1e-12 * out.projection.unit_to_metre)
            throw InvalidInput("vertical CRS \"" + shown(name_of(*vertical)) + "\" has a unit of " + format_number(v) +
                               " m but the horizontal CRS one of " + format_number(out.projection.unit_to_metre) +
                               " m; only compound CRSs with one unit for both are supported");
    }
    return out;
}

std::string trimmed(const std::string& s)
{
    const auto space = [](unsigned char c) { return std::isspace(c) != 0; };
    auto first = std::find_if_not(s.begin(), s.end(), space);
    auto last = std::find_if_not(s.rbegin(), std::string::const_reverse_iterator(first), space).base();
    return std::string(first, last);
}

} // namespace

std::optional<ProjectedCrs> crs_from_epsg(int code)
{
    const Ellipsoid wgs84{};
    const Ellipsoid grs80{6378137.0, 298.257222101};
    const auto zone_crs = [code](const std::string& name, const Ellipsoid& e, int zone, bool south) {
        ProjectedCrs c;
        c.name = name;
        c.epsg = code;
        c.projection.ellipsoid = e;
        c.projection.central_meridian_deg = -183.0 + 6.0 * zone;
        c.projection.latitude_of_origin_deg = 0.0;
        c.projection.scale_factor = 0.9996;
        c.projection.false_easting = 500000.0;
        c.projection.false_northing = south ? 10000000.0 : 0.0;
        return c;
    };
    const auto utm = [&](const char* datum, const Ellipsoid& e, int zone, bool south) {
        return zone_crs(std::string(datum) + " / UTM zone " + std::to_string(zone) + (south ? "S" : "N"), e, zone,
                        south);
    };
    const auto mga = [&](const char* datum, int zone) {
        return zone_crs(std::string(datum) + " / MGA zone " + std::to_string(zone), grs80, zone, true);
    };
    if (code >= 32601 && code <= 32660)
        return utm("WGS 84", wgs84, code - 32600, false);
    if (code >= 32701 && code <= 32760)
        return utm("WGS 84", wgs84, code - 32700, true);
    if (code >= 26901 && code <= 26923)
        return utm("NAD83", grs80, code - 26900, false);
    if (code >= 25828 && code <= 25838)
        return utm("ETRS89", grs80, code - 25800, false);
    if (code >= 28348 && code <= 28358)
        return mga("GDA94", code - 28300);
    if (code >= 7846 && code <= 7859)
        return mga("GDA2020", code - 7800);
    return std::nullopt;
}

ProjectedCrs parse_crs(const std::string& text)
{
    const std::string t = one_line(trimmed(text));
    if (t.empty())
        throw InvalidInput("CRS is empty: give EPSG:<code> (e.g. EPSG:32633) or WKT");
    if (t.size() >= 5 && normalized_name(t.substr(0, 5)) == "epsg:") {
        const std::string digits = trimmed(t.substr(5));
        const int code = parse_code(digits);
        if (code < 0)
            throw InvalidInput("CRS \"" + shown(t) + "\": the EPSG code must be a number, e.g. EPSG:32633");
        if (std::optional<ProjectedCrs> crs = crs_from_epsg(code))
            return *crs;
        // Lidar files in longitude/latitude are common enough to deserve their own hint: meshing
        // degrees against metres of height distorts the surface, whatever the placement.
        for (const int geographic : {4326, 4979, 4269, 4258, 4283, 7844, 4617, 4167})
            if (code == geographic)
                throw InvalidInput("EPSG:" + digits + " is geographic (longitude/latitude in degrees): reproject "
                                   "the points to a projected CRS such as UTM first (pdal translate, las2las)");
        throw InvalidInput("EPSG:" + digits + " is not a supported projected CRS (supported: WGS 84 / UTM "
                           "32601-32660 and 32701-32760, NAD83 / UTM 26901-26923, ETRS89 / UTM 25828-25838, "
                           "GDA94 / MGA 28348-28358, GDA2020 / MGA 7846-7859); give a Transverse Mercator CRS "
                           "as WKT or place the tileset with --enu");
    }
    if (std::isalpha(static_cast<unsigned char>(t.front())) && t.find_first_of("[(") != std::string::npos)
        return parse_wkt(t);
    throw InvalidInput("CRS \"" + shown(t, 43) + "\" is neither EPSG:<code> nor WKT (write a bare code such as 32633 as "
                       "EPSG:32633)");
}

namespace {

// The code of "EPSG:N" (any case, blanks around N), else -1.
int epsg_text_code(const std::string& text)
{
    const std::string t = trimmed(text);
    return t.size() > 5 && normalized_name(t.substr(0, 5)) == "epsg:" ? parse_code(trimmed(t.substr(5))) : -1;
}

std::optional<ProjectedCrs> try_parse_crs(const std::string& text)
{
    try {
        return parse_crs(text);
    } catch (const InvalidInput&) {
        return std::nullopt;
    }
}

bool nearly_equal(double a, double b, double relative)
{
    return std::fabs(a - b) <= relative * std::max({std::fabs(a), std::fabs(b), 1.0});
}

} // namespace

bool crs_differ(const std::string& a, const std::string& b)
{
    const int code_a = epsg_text_code(a), code_b = epsg_text_code(b);
    if (code_a >= 0 && code_b >= 0)
        return code_a != code_b;
    const std::optional<ProjectedCrs> pa = try_parse_crs(a), pb = try_parse_crs(b);
    if (!pa || !pb)
        return false;
    if (pa->epsg > 0 && pb->epsg > 0)
        return pa->epsg != pb->epsg;
    // A WKT without a known EPSG id: compared by what places the points. WKT writers round to about
    // 12 digits (the degree's 0.0174532925199433); the parameters of two systems differ far more
    // (GRS80's and WGS 84's inverse flattening in the sixth decimal, zones by 6 degrees).
    const TransverseMercator& x = pa->projection;
    const TransverseMercator& y = pb->projection;
    constexpr double kRounding = 1e-10;
    return !nearly_equal(x.ellipsoid.a, y.ellipsoid.a, kRounding) ||
           !nearly_equal(x.ellipsoid.inverse_flattening, y.ellipsoid.inverse_flattening, kRounding) ||
           !nearly_equal(wrap_degrees(x.central_meridian_deg - y.central_meridian_deg), 0.0, kRounding) ||
           !nearly_equal(x.latitude_of_origin_deg, y.latitude_of_origin_deg, kRounding) ||
           !nearly_equal(x.scale_factor, y.scale_factor, kRounding) ||
           !nearly_equal(x.unit_to_metre, y.unit_to_metre, kRounding) ||
           !nearly_equal(x.false_easting * x.unit_to_metre, y.false_easting * y.unit_to_metre, kRounding) ||
           !nearly_equal(x.false_northing * x.unit_to_metre, y.false_northing * y.unit_to_metre, kRounding);
}

std::string crs_label(const std::string& text)
{
    if (epsg_text_code(text) >= 0)
        return shown(trimmed(text));
    if (const std::optional<ProjectedCrs> c = try_parse_crs(text))
        return crs_label(*c);
    return shown(trimmed(text), 60);
}

std::string crs_label(const ProjectedCrs& crs)
{
    return crs.name + (crs.epsg > 0 ? " (EPSG:" + std::to_string(crs.epsg) + ")" : std::string());
}

Geodetic projected_to_geodetic(const TransverseMercator& tm, double easting, double northing, double height)
{
    check_projection(tm, "projected_to_geodetic");
    if (!(std::isfinite(easting) && std::isfinite(northing) && std::isfinite(height)))
        throw InvalidInput("projected_to_geodetic: easting, northing and height must be finite");
    const Series s = make_series(tm.ellipsoid);
    const double u = tm.unit_to_metre, k0 = tm.scale_factor;
    const double xi = ((northing - tm.false_northing) * u / k0 + origin_northing(s, tm.latitude_of_origin_deg)) / s.A;
    const double eta = (easting - tm.false_easting) * u / (k0 * s.A);
    double xip = xi, etap = eta;
    for (int j = 1; j <= 6; ++j) {
        const double k = 2.0 * j;
        xip -= s.beta[j - 1] * std::sin(k * xi) * std::cosh(k * eta);
        etap -= s.beta[j - 1] * std::cos(k * xi) * std::sinh(k * eta);
    }
    const double sh = std::sinh(etap), c = std::cos(xip);
    const double r = std::hypot(sh, c);
    Geodetic g;
    g.height = height * u;
    if (r == 0.0) { // exactly a pole
        g.latitude_deg = std::sin(xip) > 0.0 ? 90.0 : -90.0;
        g.longitude_deg = wrap_degrees(tm.central_meridian_deg);
    } else {
        g.latitude_deg = std::atan(tauf(s, std::sin(xip) / r)) / kDegree;
        g.longitude_deg = wrap_degrees(tm.central_meridian_deg + std::atan2(sh, c) / kDegree);
    }
    if (!(std::isfinite(g.latitude_deg) && std::isfinite(g.longitude_deg) && std::isfinite(g.height)))
        throw InvalidInput("projected_to_geodetic: (" + format_number(easting) + ", " + format_number(northing) +
                           ") is too far from the central meridian " + format_number(tm.central_meridian_deg) +
                           "° for Transverse Mercator; check the CRS");
    return g;
}

Vec3 geodetic_to_projected(const TransverseMercator& tm, const Geodetic& g)
{
    check_projection(tm, "geodetic_to_projected");
    check_geodetic(g, "geodetic_to_projected");
    const Series s = make_series(tm.ellipsoid);
    const double lambda = wrap_degrees(g.longitude_deg - tm.central_meridian_deg) * kDegree;
    const double taup = taupf(s, std::tan(g.latitude_deg * kDegree));
    const double cl = std::cos(lambda);
    const double xip = std::atan2(taup, cl);
    const double etap = std::asinh(std::sin(lambda) / std::hypot(taup, cl));
    double xi = 0, eta = 0;
    krueger_forward(s, xip, etap, xi, eta);
    const double u = tm.unit_to_metre, k0 = tm.scale_factor;
    const Vec3 p{tm.false_easting + k0 * s.A * eta / u,
                 tm.false_northing + k0 * (s.A * xi - origin_northing(s, tm.latitude_of_origin_deg)) / u,
                 g.height / u};
    if (!is_finite(p))
        throw InvalidInput("geodetic_to_projected: (" + format_number(g.longitude_deg) + ", " +
                           format_number(g.latitude_deg) + ") is 90° from the central meridian " +
                           format_number(tm.central_meridian_deg) + "°, where Transverse Mercator is infinite");
    return p;
}

Vec3 geodetic_to_ecef(const Ellipsoid& e, const Geodetic& g)
{
    check_geodetic(g, "geodetic_to_ecef");
    const double f = flattening(e);
    const double e2 = f * (2.0 - f);
    const double phi = g.latitude_deg * kDegree, lambda = g.longitude_deg * kDegree;
    const double sp = std::sin(phi), cp = std::cos(phi);
    const double n = e.a / std::sqrt(1.0 - e2 * sp * sp); // prime vertical radius of curvature
    return {(n + g.height) * cp * std::cos(lambda), (n + g.height) * cp * std::sin(lambda),
            (n * (1.0 - e2) + g.height) * sp};
}

EnuFrame::EnuFrame(const Ellipsoid& e, const Geodetic& anchor)
    : anchor_(anchor), origin_(geodetic_to_ecef(e, anchor))
{
    const double phi = anchor.latitude_deg * kDegree, lambda = anchor.longitude_deg * kDegree;
    const double sp = std::sin(phi), cp = std::cos(phi), sl = std::sin(lambda), cl = std::cos(lambda);
    east_ = {-sl, cl, 0.0};
    north_ = {-sp * cl, -sp * sl, cp};
    up_ = {cp * cl, cp * sl, sp};
}

Vec3 EnuFrame::ecef_to_enu(const Vec3& ecef) const
{
    const Vec3 d = ecef - origin_;
    return {dot(east_, d), dot(north_, d), dot(up_, d)};
}

std::array<double, 16> EnuFrame::enu_to_ecef() const
{
    return {east_.x, east_.y, east_.z, 0.0,   north_.x,  north_.y,  north_.z,  0.0,
            up_.x,   up_.y,   up_.z,   0.0,   origin_.x, origin_.y, origin_.z, 1.0};
}

const Geodetic& EnuFrame::anchor() const { return anchor_; }

} // namespace mrt
