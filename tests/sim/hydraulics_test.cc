#include "sim/hydraulics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace canalid::sim {
namespace {

TEST(TrapezoidSection, GeometryMatchesClosedForms) {
  const TrapezoidSection s(7.0, 1.5, 0.02);
  // Canal 2 pool 2 at 2.1 m: A = (7 + 1.5*2.1)*2.1, T = 7 + 3*2.1, P = 7 + 2*2.1*sqrt(3.25).
  EXPECT_DOUBLE_EQ(s.Area(2.1), (7.0 + 1.5 * 2.1) * 2.1);
  EXPECT_DOUBLE_EQ(s.TopWidth(2.1), 7.0 + 3.0 * 2.1);
  EXPECT_DOUBLE_EQ(s.Perimeter(2.1), 7.0 + 2.0 * 2.1 * std::sqrt(3.25));
  const double a = s.Area(2.1);
  const double r = a / s.Perimeter(2.1);
  // Manning: Sf = n^2 Q^2 / (A^2 R^(4/3)).
  EXPECT_NEAR(s.FrictionSlope(2.1, 10.0), 0.0004 * 100.0 / (a * a * std::pow(r, 4.0 / 3.0)), 1e-15);
  EXPECT_LT(s.FrictionSlope(2.1, -10.0), 0.0);
}

TEST(TrapezoidSection, FrictionDerivativesMatchFiniteDifferences) {
  const TrapezoidSection s(5.0, 1.5, 0.02);
  double g, gh, gq, gp, gm, unused1, unused2;
  s.Friction(1.7, 6.0, &g, &gh, &gq);
  const double e = 1e-6;
  s.Friction(1.7 + e, 6.0, &gp, &unused1, &unused2);
  s.Friction(1.7 - e, 6.0, &gm, &unused1, &unused2);
  // Central differences are accurate to ~e^2 * G''' relative; 1e-6 relative is ample.
  EXPECT_NEAR(gh, (gp - gm) / (2 * e), 1e-6 * std::abs(gh));
  s.Friction(1.7, 6.0 + e, &gp, &unused1, &unused2);
  s.Friction(1.7, 6.0 - e, &gm, &unused1, &unused2);
  EXPECT_NEAR(gq, (gp - gm) / (2 * e), 1e-6 * std::abs(gq));
}

TEST(TrapezoidSection, RejectsBadGeometry) {
  EXPECT_THROW(TrapezoidSection(0.0, 0.0, 0.02), std::invalid_argument);
  EXPECT_THROW(TrapezoidSection(1.0, -1.0, 0.02), std::invalid_argument);
  EXPECT_THROW(TrapezoidSection(1.0, 1.0, 0.0), std::invalid_argument);
}

TEST(StructureFlow, UndershotGateFreeAndSubmerged) {
  Structure gate;
  gate.type = Structure::Type::kUndershotGate;
  gate.width_m = 7.0;
  gate.coefficient = 0.6;
  const double k = 0.6 * 7.0 * 0.5 * std::sqrt(2.0 * kGravity);
  // Submerged (tailwater 1.9 m above a 0.5 m lip): head is the level difference.
  EXPECT_NEAR(StructureFlow(gate, 0.5, 2.1, 1.9), k * std::sqrt(0.2), 1e-12);
  // Free (tailwater 0.2 m below the lip): head measured to the lip.
  EXPECT_NEAR(StructureFlow(gate, 0.5, 2.1, 0.2), k * std::sqrt(1.6), 1e-12);
  // Reverse head gives reverse flow of the same law.
  EXPECT_NEAR(StructureFlow(gate, 0.5, 1.9, 2.1), -k * std::sqrt(0.2), 1e-12);
}

TEST(StructureFlow, WeirFreeSubmergedAndPump) {
  Structure weir;
  weir.type = Structure::Type::kWeir;
  weir.width_m = 5.0;
  weir.coefficient = 1.7;
  EXPECT_NEAR(StructureFlow(weir, 1.2, 1.7, -1.0), 1.7 * 5.0 * std::pow(0.5, 1.5), 1e-12);
  EXPECT_EQ(StructureFlow(weir, 1.8, 1.7, -1.0), 0.0);
  // Villemonte: H2/H1 = 0.5.
  EXPECT_NEAR(StructureFlow(weir, 1.2, 1.7, 1.45),
              1.7 * 5.0 * std::pow(0.5, 1.5) * std::pow(1.0 - std::pow(0.5, 1.5), 0.385), 1e-12);
  Structure pump;
  pump.type = Structure::Type::kPump;
  EXPECT_EQ(StructureFlow(pump, 3.5, 0.1, 9.0), 3.5);
}

TEST(SteadyStructureSetting, InvertsTheStructureLaw) {
  Structure gate;
  gate.width_m = 7.0;
  const double u = SteadyStructureSetting(gate, 10.0, 2.1, 1.95);
  EXPECT_NEAR(StructureFlow(gate, u, 2.1, 1.95), 10.0, 1e-9);
  EXPECT_GT(u, 0.0);
  Structure weir;
  weir.type = Structure::Type::kWeir;
  weir.width_m = 7.0;
  weir.coefficient = 1.7;
  const double crest = SteadyStructureSetting(weir, 10.0, 2.1, -1000.0);
  // Free weir closed form: crest = y - (Q / (Cw w))^(2/3).
  EXPECT_NEAR(crest, 2.1 - std::pow(10.0 / (1.7 * 7.0), 2.0 / 3.0), 1e-9);
  // A gate cannot pass flow against the head.
  EXPECT_THROW(SteadyStructureSetting(gate, 10.0, 1.9, 2.1), std::invalid_argument);
}

TEST(OfftakeFlow, FixedAndOrifice) {
  Offtake fixed;
  fixed.type = Offtake::Type::kFixedFlow;
  EXPECT_EQ(OfftakeFlow(fixed, 1.0, 2.0), 1.0);
  EXPECT_EQ(OfftakeFlow(fixed, 1.0, 0.0), 0.0);
  Offtake orifice;
  orifice.type = Offtake::Type::kOrifice;
  orifice.outlet_m = 0.5;
  EXPECT_NEAR(OfftakeFlow(orifice, 0.2, 2.1), 0.6 * 0.2 * std::sqrt(2 * kGravity * 1.6), 1e-12);
}

}  // namespace
}  // namespace canalid::sim
