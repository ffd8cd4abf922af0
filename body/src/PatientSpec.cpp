// Validation of the patient section and parsing of its enumerations.
#include "body/PatientSpec.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace body {
namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

std::string fmt(double v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

}  // namespace

const char* getPostureName(Posture p) {
    switch (p) {
        case Posture::Supine:
            return "supine";
        case Posture::TiltLeft30:
            return "tilt-left-30";
        case Posture::TiltRight30:
            return "tilt-right-30";
        case Posture::SideLeft90:
            return "side-left-90";
        case Posture::SideRight90:
            return "side-right-90";
        case Posture::HeadOfBedRaised:
            return "head-of-bed-raised";
    }
    return "?";
}

const char* getPostureNames() {
    return "supine, tilt-left-30, tilt-right-30, side-left-90, side-right-90, head-of-bed-raised";
}

Posture parsePosture(const std::string& name) {
    const std::string n = lower(name);
    for (Posture p : {Posture::Supine, Posture::TiltLeft30, Posture::TiltRight30,
                      Posture::SideLeft90, Posture::SideRight90, Posture::HeadOfBedRaised})
        if (n == getPostureName(p)) return p;
    throw std::invalid_argument("patient.posture: '" + name +
                                "' is not a posture; valid: " + getPostureNames());
}

Sex parseSex(const std::string& name) {
    const std::string n = lower(name);
    if (n == "female" || n == "f") return Sex::Female;
    if (n == "male" || n == "m") return Sex::Male;
    throw std::invalid_argument("patient.sex: '" + name + "' is not valid; use female or male");
}

double PatientSpec::getBodySurfaceArea() const { return std::sqrt(height * 100.0 * mass / 3600.0); }

void PatientSpec::validate() const {
    if (sex != Sex::Female && sex != Sex::Male)
        throw std::invalid_argument("patient.sex: must be female or male");
    if (!std::isfinite(height) || height < 1.4 || height > 2.1)
        throw std::invalid_argument("patient.height: " + fmt(height) +
                                    " m is outside 1.4-2.1 m, the range the de Leva scaling is "
                                    "used for (give the stature in metres)");
    if (!std::isfinite(mass) || !(mass > 0))
        throw std::invalid_argument("patient.mass: " + fmt(mass) +
                                    " kg is not a positive mass in kilograms");
    const double bmi = getBmi();
    if (bmi < 14 - 1e-9 || bmi > 50 + 1e-9)  // tolerance: 14 * h * h / (h * h) may round below 14
        throw std::invalid_argument(
            "patient.mass: " + fmt(mass) + " kg at " + fmt(height) + " m gives a BMI of " +
            fmt(std::round(bmi * 10) / 10) + " kg/m^2, outside the modelled 14-50 (mass between " +
            fmt(std::round(14 * height * height * 10) / 10) + " and " +
            fmt(std::round(50 * height * height * 10) / 10) + " kg at this height)");
    if (!std::isfinite(position[0]) || !std::isfinite(position[1]))
        throw std::invalid_argument(
            "patient.position: must be two finite numbers [x, y] in metres");
    const double deg = headOfBedAngle * 180.0 / 3.14159265358979323846;
    if (!std::isfinite(deg) || deg < 0 || deg > 80)
        throw std::invalid_argument("patient.head_of_bed_angle: " + fmt(deg) +
                                    " deg is outside 0-80 deg");
}

}  // namespace body
