// The one table of physical constants of the weather generator. Every entry names its source and
// unit; tests/generator/physics_test.cc checks each against numbers published with (or derived
// from) that source. Units: D in mm, R in mm/h, N(D) in m^-3 mm^-1, speeds in m/s unless a name says
// otherwise.
#pragma once

#include "core/constants.h"

namespace weathergs::generator::physics {

// Marshall & Palmer (1948), J. Meteor. 5:165, "The distribution of raindrops with size":
// N(D) = N0 exp(-Lambda D), N0 = 0.08 cm^-4, Lambda = 41 R^-0.21 cm^-1.
constexpr double kMarshallPalmerN0_m3_mm = 8000.0;       // 0.08 cm^-4 = 8000 m^-3 mm^-1
constexpr double kMarshallPalmerLambdaCoef_per_mm = 4.1;  // 41 cm^-1 = 4.1 mm^-1
constexpr double kMarshallPalmerLambdaExp = -0.21;        // exponent of R (mm/h)

// Atlas, Srivastava & Sekhon (1973), Rev. Geophys. Space Phys. 11:1, fit to Gunn & Kinzer (1949):
// v(D) = 9.65 - 10.3 exp(-0.6 D), D in mm, v in m/s (negative below D = 0.109 mm: clamped at 0).
constexpr double kAtlasA_m_s = 9.65;
constexpr double kAtlasB_m_s = 10.3;
constexpr double kAtlasC_per_mm = 0.6;

// Gunn & Marshall (1958), J. Meteor. 15:452, snow by melted diameter D, R water equivalent (mm/h):
// N0 = 3.8e3 R^-0.87 m^-3 mm^-1, Lambda = 25.5 R^-0.48 cm^-1 = 2.55 R^-0.48 mm^-1 (the paper gives
// cm^-1; implementations that keep 25.5 with D in mm make flakes ten times too small).
constexpr double kGunnMarshallN0Coef_m3_mm = 3800.0;
constexpr double kGunnMarshallN0Exp = -0.87;
constexpr double kGunnMarshallLambdaCoef_per_mm = 2.55;
constexpr double kGunnMarshallLambdaExp = -0.48;

// Locatelli & Hobbs (1974), J. Geophys. Res. 79:2185, aggregates of unrimed radiating assemblages
// of dendrites: v = 0.8 D^0.16, D = maximum dimension in mm, v in m/s.
constexpr double kLocatelliHobbsCoef_m_s = 0.8;
constexpr double kLocatelliHobbsExp = 0.16;

// Holroyd (1971) snowflake density law, as used in radar snow studies: rho = 0.170 / D g cm^-3 with
// D the flake diameter in cm. Capped at the density of ice (flakes below ~1.85 mm).
constexpr double kHolroydCoef_g_cm2 = 0.170;
constexpr double kIceDensity_g_cm3 = 0.917;   // ice Ih at 0 C (CRC Handbook of Chemistry and Physics)
constexpr double kWaterDensity_g_cm3 = 1.0;

// Beard & Chuang (1987), J. Atmos. Sci. 44:1509: equilibrium raindrop axis ratio b/a, polynomial
// fit in D (cm): b/a = 1.0048 + 0.0057 D - 2.628 D^2 + 3.682 D^3 - 1.677 D^4 (1 <= D <= 9 mm).
constexpr double kBeardChuang_cm[5] = {1.0048, 0.0057, -2.628, 3.682, -1.677};

// Koschmieder (1924): visibility V at which a black object's contrast falls to 2%:
// V = -ln(0.02) / beta = 3.912 / beta.
constexpr double kKoschmiederContrast = 0.02;
constexpr double kKoschmiederConstant = 3.912;

// Optical extinction by rain, beta = 0.312 R^0.67 km^-1 (the specified model). Cross-checked in the tests
// against geometric optics (extinction efficiency 2) integrated over Marshall-Palmer.
constexpr double kRainExtinctionCoef_per_km = 0.312;
constexpr double kRainExtinctionExp = 0.67;

// Standard gravity (3rd CGPM, 1901), m/s^2.
constexpr double kGravity_m_s2 = 9.80665;

// Rain rate from a drop-size distribution: R = 6e-4 pi Int N(D) D^3 v(D) dD  [mm/h]
// = 3.6e6 (mm/h per m/s) * 1e-9 (m^3 per mm^3) * pi/6 (sphere volume / D^3).
constexpr double kRainRateFactor = 6e-4 * kPi;

// Named intensities (a weather spec's "intensity" instead of "rate_mm_h"), docs/generator.md.
// Rain: the WMO reference classes of rain rate (WMO Guide to Instruments and Methods of Observation,
// WMO-No. 8, as adopted by national services; the US AMS glossary uses 2.5 / 7.6 mm/h): light <= 2.5,
// moderate 2.5-10, heavy 10-50, violent > 50 mm/h. The rate used for class i is the geometric mean of
// bounds i and i + 1: light spans 0.25-2.5 (0.25 being the "very light" limit) and the open-ended
// class gets 2x its lower bound as the upper one. Rain: 0.79, 5.0, 22.4, 70.7 mm/h.
constexpr double kRainClassBounds_mm_h[5] = {0.25, 2.5, 10.0, 50.0, 100.0};
// Snow, by water-equivalent rate: light < 1, moderate 1-5, heavy >= 5 mm/h (the usual practice of
// weather services; not confirmed here from a primary source). Snow intensity is also defined by
// visibility (AMS glossary, US NWS: light > 1 km, moderate 0.5-1 km, heavy < 0.5 km); the generator
// reports the visibility its particles give in docs/scenes.md. There is no "violent" snow class: we
// define it as >= 4x the heavy threshold (20 mm/h, the rate of intense lake-effect bands). Same
// geometric-mean rule: snow 0.5, 2.24, 10.0, 28.3 mm/h water equivalent.
constexpr double kSnowClassBounds_mm_h[5] = {0.25, 1.0, 5.0, 20.0, 40.0};

}  // namespace weathergs::generator::physics
