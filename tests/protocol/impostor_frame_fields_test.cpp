// ImpostorRequest's fixed-frame fields (an imposter node with autocenter /
// autosize FALSE, Pasman & Jansen 2002 Figure 9): round trip, absence means
// "framed from the objects", and the validator's rules.
#include <gtest/gtest.h>

#include <limits>

#include "thinlod/protocol/codec.h"

namespace thinlod::protocol {
namespace {

ImpostorRequest frameRequest() {
  ImpostorRequest r;
  r.requestId = 9;
  r.objectIds = {1, 2};
  r.eye = {0.0f, 1.0f, 10.0f};
  r.accuracyBound = 0.01;
  return r;
}

Result<Message> roundTrip(const Message& message) {
  Result<std::vector<std::uint8_t>> bytes = encode(message);
  if (!bytes.ok()) return bytes.status();
  return decode(bytes->data(), bytes->size());
}

TEST(ImpostorFrameFields, RoundTripWithAndWithoutAFixedFrame) {
  ImpostorRequest fixed = frameRequest();
  fixed.frameCenter = glm::vec3(0.5f, 1.0f, -2.0f);
  fixed.frameWidth = 2.0f;
  fixed.frameHeight = 1.5f;
  for (const ImpostorRequest& request : {frameRequest(), fixed}) {
    Result<Message> decoded = roundTrip(Message(request));
    ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
    EXPECT_TRUE(*decoded == Message(request));
  }
  Result<Message> automatic = roundTrip(Message(frameRequest()));
  ASSERT_TRUE(automatic.ok());
  const auto& back = std::get<ImpostorRequest>(*automatic);
  EXPECT_FALSE(back.frameCenter.has_value());
  EXPECT_EQ(back.frameWidth, 0.0f);
  EXPECT_EQ(back.frameHeight, 0.0f);
}

TEST(ImpostorFrameFields, SizesAreBothPositiveOrBothZeroAndCentresFinite) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  struct Size {
    float w, h;
  };
  for (Size bad : {Size{1.0f, 0.0f}, Size{0.0f, 2.0f}, Size{-1.0f, -1.0f}, Size{nan, 1.0f},
                   Size{1.0f, inf}}) {
    ImpostorRequest r = frameRequest();
    r.frameWidth = bad.w;
    r.frameHeight = bad.h;
    EXPECT_EQ(validate(Message(r)).code(), ErrorCode::kInvalidArgument) << bad.w << " " << bad.h;
  }
  ImpostorRequest centre = frameRequest();
  centre.frameCenter = glm::vec3(nan, 0.0f, 0.0f);
  EXPECT_EQ(validate(Message(centre)).code(), ErrorCode::kInvalidArgument);
  ImpostorRequest good = frameRequest();
  good.frameCenter = glm::vec3(1.0f);
  good.frameWidth = 0.5f;
  good.frameHeight = 0.25f;
  EXPECT_TRUE(validate(Message(good)).ok());
}

}  // namespace
}  // namespace thinlod::protocol
