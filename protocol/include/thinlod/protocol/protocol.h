// thinlod protocol module: what the daemons exchange and how.
//
//   messages.h         plain structs of every message, limits, version
//   codec.h            encode / decode / validate (pure, bounded, verified)
//   transport.h        Endpoint (ROUTER, binds), Channel (DEALER, connects),
//                      Poller, WorkerPool (backbone -> simplifier workers)
//   pending_requests.h the WorkerPool's pure request table
//   link_shaper.h      token bucket + per-frame accounting + link budget
//   daemon_runtime.h   options (TOML + flags), logging, signals
//
// Contract, common to all of them:
// - Bytes from a peer are untrusted: decode() checks size, FlatBuffers
//   verification, version and every field before a message exists; a bad
//   message is a Status (naming the field), logged and dropped by the
//   transport, never a crash or an exception.
// - Expected failures are Status / Result<T> with thinlod::ErrorCode, which
//   maps one-to-one onto the wire. Contract violations assert.
// - Units: nanoseconds (steady clock), metres, radians, bytes, pixels;
//   accuracy a = 1/d (accuracy_curve.h).
// - No FlatBuffers or ZeroMQ type appears in these headers.
// - Pure parts (messages, codec, shaper, request table) are thread-safe as
//   values; sockets (Endpoint, Channel, WorkerPool) belong to one thread.
// Reference: docs/protocol.md.
#pragma once

#include "thinlod/protocol/codec.h"
#include "thinlod/protocol/daemon_runtime.h"
#include "thinlod/protocol/link_shaper.h"
#include "thinlod/protocol/messages.h"
#include "thinlod/protocol/pending_requests.h"
#include "thinlod/protocol/transport.h"
