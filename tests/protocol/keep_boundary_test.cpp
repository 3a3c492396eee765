// SimplifyRequest::keepBoundary (a region object's levels keep its borders,
// docs/regions.md): round trip, default false, and Mesh only.
#include <gtest/gtest.h>

#include "thinlod/protocol/codec.h"

namespace thinlod::protocol {
namespace {

SimplifyRequest regionRequest() {
  SimplifyRequest r;
  r.requestId = 3;
  r.objectId = 4;
  r.sourcePath = "scene.wrl";
  r.targetTriangles = 100;
  r.keepBoundary = true;
  return r;
}

Result<Message> roundTrip(const Message& message) {
  Result<std::vector<std::uint8_t>> bytes = encode(message);
  if (!bytes.ok()) return bytes.status();
  return decode(bytes->data(), bytes->size());
}

TEST(KeepBoundaryWireField, RoundTripsBothValues) {
  for (bool keep : {true, false}) {
    SimplifyRequest request = regionRequest();
    request.keepBoundary = keep;
    Result<Message> decoded = roundTrip(Message(request));
    ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
    ASSERT_TRUE(std::holds_alternative<SimplifyRequest>(*decoded));
    EXPECT_EQ(std::get<SimplifyRequest>(*decoded).keepBoundary, keep);
    EXPECT_TRUE(*decoded == Message(request));
  }
  EXPECT_FALSE(SimplifyRequest().keepBoundary);
}

TEST(KeepBoundaryWireField, FlagDistinguishesOtherwiseEqualRequests) {
  SimplifyRequest plain = regionRequest();
  plain.keepBoundary = false;
  EXPECT_FALSE(Message(plain) == Message(regionRequest()));
}

TEST(KeepBoundaryWireField, AppliesToMeshRequestsOnly) {
  EXPECT_TRUE(validate(Message(regionRequest())).ok());
  SimplifyRequest hybrid = regionRequest();
  hybrid.representation = RepresentationKind::kHybrid;
  const Status refused = validate(Message(hybrid));
  EXPECT_EQ(refused.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(refused.message().find("keep_boundary"), std::string::npos) << refused.message();
  hybrid.keepBoundary = false;
  EXPECT_TRUE(validate(Message(hybrid)).ok());
}

}  // namespace
}  // namespace thinlod::protocol
