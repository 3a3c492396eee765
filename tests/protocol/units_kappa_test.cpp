// SceneUpdate::unitsKappa (the kappa the plan's polygon budget counts hybrid
// points with, so the frontend reports units without being told): round
// trip, default 0, and its range.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "thinlod/protocol/codec.h"

namespace thinlod::protocol {
namespace {

Result<Message> roundTrip(const Message& message) {
  Result<std::vector<std::uint8_t>> bytes = encode(message);
  if (!bytes.ok()) return bytes.status();
  return decode(bytes->data(), bytes->size());
}

SceneUpdate updateWithKappa(double kappa) {
  SceneUpdate update;
  update.plan = 4;
  update.frame = 9;
  update.targetAccuracy = 20.0;
  update.unitsKappa = kappa;
  return update;
}

TEST(UnitsKappaWireField, RoundTripsAndDefaultsToZero) {
  EXPECT_EQ(SceneUpdate().unitsKappa, 0.0);
  for (double kappa : {0.0, 1.0, 1.5, 3.0, kMaxKappa}) {
    Result<Message> decoded = roundTrip(Message(updateWithKappa(kappa)));
    ASSERT_TRUE(decoded.ok()) << kappa << ": " << decoded.status().toString();
    ASSERT_TRUE(std::holds_alternative<SceneUpdate>(*decoded));
    EXPECT_EQ(std::get<SceneUpdate>(*decoded).unitsKappa, kappa);
  }
  EXPECT_FALSE(Message(updateWithKappa(3.0)) == Message(updateWithKappa(1.5)));
}

TEST(UnitsKappaWireField, OutsideZeroOrOneToMaxIsRefusedNamingTheField) {
  for (double kappa : {-1.0, 0.5, kMaxKappa + 1.0, std::nan(""),
                       std::numeric_limits<double>::infinity()}) {
    const Status refused = validate(Message(updateWithKappa(kappa)));
    EXPECT_EQ(refused.code(), ErrorCode::kInvalidArgument) << kappa;
    EXPECT_NE(refused.message().find("units_kappa"), std::string::npos) << refused.message();
  }
}

}  // namespace
}  // namespace thinlod::protocol
