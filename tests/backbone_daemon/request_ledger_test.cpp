// RequestLedger (backbone/src/daemon/request_ledger.h): one id per request,
// its states, and what happens to duplicate, late and unknown replies.
#include "request_ledger.h"

#include <gtest/gtest.h>

#include <string>

namespace thinlod::backbone_daemon {
namespace {

LedgerRequest planRequest(std::uint64_t id, std::uint32_t option, std::uint64_t pose = 1) {
  LedgerRequest r;
  r.id = id;
  r.purpose = RequestPurpose::kPlan;
  r.object = option;
  r.option = option;
  r.pose = pose;
  return r;
}

bool mentions(const Status& status, const std::string& text) {
  return status.message().find(text) != std::string::npos;
}

TEST(RequestLedger, ARequestGoesAskedInFlightAnsweredUnderItsOneId) {
  RequestLedger ledger;
  auto asked = ledger.ask(planRequest(41, 3));
  ASSERT_TRUE(asked.ok()) << asked.status().toString();
  EXPECT_FALSE(asked->has_value());  // replaced nothing
  EXPECT_EQ(ledger.state(41), RequestState::kAsked);
  EXPECT_TRUE(ledger.submitted(41));
  EXPECT_FALSE(ledger.submitted(41));  // only once
  EXPECT_EQ(ledger.state(41), RequestState::kInFlight);
  EXPECT_EQ(ledger.openForOption(3)->id, 41u);
  EXPECT_EQ(ledger.openPlanRequestsOfPose(1), 1u);

  Result<LedgerRequest> claimed = ledger.claim(41);
  ASSERT_TRUE(claimed.ok()) << claimed.status().toString();
  EXPECT_EQ(claimed->id, 41u);
  EXPECT_EQ(claimed->option, 3u);
  EXPECT_EQ(ledger.state(41), RequestState::kAnswered);
  EXPECT_EQ(ledger.openCount(), 0u);
  EXPECT_EQ(ledger.openForOption(3), nullptr);
  EXPECT_EQ(ledger.closedCount(RequestState::kAnswered), 1u);
}

TEST(RequestLedger, IdZeroAndKnownIdsAreRefused) {
  RequestLedger ledger;
  EXPECT_EQ(ledger.ask(planRequest(0, 1)).status().code(), ErrorCode::kInvalidArgument);
  ASSERT_TRUE(ledger.ask(planRequest(7, 1)).ok());
  EXPECT_EQ(ledger.ask(planRequest(7, 2)).status().code(), ErrorCode::kInvalidArgument);
  ASSERT_TRUE(ledger.claim(7).ok());
  // A closed id is still known: never asked twice.
  EXPECT_EQ(ledger.ask(planRequest(7, 2)).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(ledger.openCount(), 0u);
}

TEST(RequestLedger, DuplicateReplyIsRefusedAndChangesNothing) {
  RequestLedger ledger;
  ASSERT_TRUE(ledger.ask(planRequest(9, 0)).ok());
  ledger.submitted(9);
  ASSERT_TRUE(ledger.claim(9).ok());
  Result<LedgerRequest> again = ledger.claim(9);
  EXPECT_EQ(again.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(mentions(again.status(), "duplicate reply")) << again.status().toString();
  EXPECT_EQ(ledger.state(9), RequestState::kAnswered);
  EXPECT_EQ(ledger.closedCount(RequestState::kAnswered), 1u);
}

TEST(RequestLedger, LateReplyAfterTimeoutIsRefused) {
  RequestLedger ledger;
  ASSERT_TRUE(ledger.ask(planRequest(12, 4)).ok());
  ledger.submitted(12);
  ASSERT_TRUE(ledger.close(12, RequestState::kTimedOut));
  EXPECT_FALSE(ledger.close(12, RequestState::kFailed));  // closed once
  Result<LedgerRequest> late = ledger.claim(12);
  EXPECT_EQ(late.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(mentions(late.status(), "late reply")) << late.status().toString();
  EXPECT_TRUE(mentions(late.status(), "timed out")) << late.status().toString();
  EXPECT_EQ(ledger.state(12), RequestState::kTimedOut);
  // The option is free for the scheduler's next request.
  EXPECT_EQ(ledger.openForOption(4), nullptr);
  EXPECT_TRUE(ledger.ask(planRequest(13, 4)).ok());
}

TEST(RequestLedger, UnknownIdIsNotFound) {
  RequestLedger ledger;
  ASSERT_TRUE(ledger.ask(planRequest(5, 0)).ok());
  Result<LedgerRequest> unknown = ledger.claim(6);
  EXPECT_EQ(unknown.status().code(), ErrorCode::kNotFound);
  EXPECT_TRUE(mentions(unknown.status(), "unknown request id 6")) << unknown.status().toString();
  EXPECT_EQ(ledger.state(5), RequestState::kAsked);  // untouched
  EXPECT_EQ(ledger.state(6), std::nullopt);
}

TEST(RequestLedger, AskingAgainForAnOptionRetriesUnderTheNewId) {
  RequestLedger ledger;
  ASSERT_TRUE(ledger.ask(planRequest(20, 2, 1)).ok());
  ledger.submitted(20);
  auto second = ledger.ask(planRequest(27, 2, 5));
  ASSERT_TRUE(second.ok());
  ASSERT_TRUE(second->has_value());
  EXPECT_EQ((*second)->id, 20u);
  EXPECT_EQ((*second)->state, RequestState::kInFlight);  // as it was: the caller cancels it
  EXPECT_EQ(ledger.state(20), RequestState::kRetried);
  const LedgerRequest* open = ledger.openForOption(2);
  ASSERT_NE(open, nullptr);
  EXPECT_EQ(open->id, 27u);
  EXPECT_EQ(open->retryOf, 20u);
  EXPECT_EQ(open->attempt, 2);
  // The old id's reply is late; the new one answers.
  EXPECT_TRUE(mentions(ledger.claim(20).status(), "late reply"));
  EXPECT_TRUE(ledger.claim(27).ok());
}

TEST(RequestLedger, StartupRequestsAreNotTiedToAnOption) {
  RequestLedger ledger;
  LedgerRequest curve = planRequest(1, 0);
  curve.purpose = RequestPurpose::kCurve;
  LedgerRequest warmup = planRequest(2, 0);
  warmup.purpose = RequestPurpose::kWarmup;
  ASSERT_TRUE(ledger.ask(curve).ok());
  ASSERT_TRUE(ledger.ask(warmup).ok());
  ASSERT_TRUE(ledger.ask(planRequest(3, 0)).ok());
  EXPECT_EQ(ledger.openCount(), 3u);
  EXPECT_EQ(ledger.openCount(RequestPurpose::kCurve), 1u);
  EXPECT_EQ(ledger.openForOption(0)->id, 3u);
  EXPECT_EQ(ledger.openPlanRequestsOfPose(1), 1u);
}

TEST(RequestLedger, RefusedReplyIsReclassified) {
  RequestLedger ledger;
  ASSERT_TRUE(ledger.ask(planRequest(8, 1)).ok());
  ASSERT_TRUE(ledger.claim(8).ok());
  EXPECT_TRUE(ledger.reclassify(8, RequestState::kTimedOut));
  EXPECT_FALSE(ledger.reclassify(8, RequestState::kFailed));  // only answered ones
  EXPECT_FALSE(ledger.reclassify(99, RequestState::kFailed));
  EXPECT_EQ(ledger.state(8), RequestState::kTimedOut);
  EXPECT_EQ(ledger.closedCount(RequestState::kAnswered), 0u);
  EXPECT_EQ(ledger.closedCount(RequestState::kTimedOut), 1u);
}

TEST(RequestLedger, ClosedHistoryIsBoundedOldestFirst) {
  RequestLedger ledger(3);
  for (std::uint64_t id = 1; id <= 5; ++id) {
    ASSERT_TRUE(ledger.ask(planRequest(id, static_cast<std::uint32_t>(id))).ok());
    ASSERT_TRUE(ledger.claim(id).ok());
  }
  EXPECT_EQ(ledger.state(1), std::nullopt);  // forgotten: a reply is now unknown
  EXPECT_EQ(ledger.state(2), std::nullopt);
  EXPECT_EQ(ledger.claim(1).status().code(), ErrorCode::kNotFound);
  for (std::uint64_t id = 3; id <= 5; ++id) EXPECT_EQ(ledger.state(id), RequestState::kAnswered);
  EXPECT_EQ(ledger.closedCount(RequestState::kAnswered), 5u);  // counters are not bounded
}

}  // namespace
}  // namespace thinlod::backbone_daemon
