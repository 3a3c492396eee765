// thinlod frontend library: the thin client of Pasman & Jansen (2002, section 4).
//
// - frontend_scene.h     what the client holds; atomic update batches, upload bookkeeping
// - frontend_renderer.h  draws the held scene each frame (batched, GPU-resident), reads it back
// - reference_renderer.h the full-quality frame for the same pose
// - frame_metrics.h      per-frame SNR / PSNR (the paper's formulas; pure)
// - frame_record.h       the per-frame record, frames.csv + bounded run summary (FrameLog)
// - view_camera.h        pose -> camera, shared by both renderers
//
// Typical daemon loop (one thread, one GL context current on it):
//   renderer->submit(batch) for every decoded SceneUpdate;
//   camera = cameraFromPose(...); renderer->renderFrame(camera, lighting, frame);
//   reference->render(fullScene, camera, lighting, referenceFrame);
//   compareFrames(frame, referenceFrame) -> FrameRecord::quality -> FrameLog::add.
// Units: metres, radians, milliseconds; images RGBA8 top-down. Errors are
// Status/Result; nothing throws. GL objects: context current, not thread-safe.
#pragma once

#include "thinlod/frontend/frame_metrics.h"
#include "thinlod/frontend/frame_record.h"
#include "thinlod/frontend/frontend_renderer.h"
#include "thinlod/frontend/frontend_scene.h"
#include "thinlod/frontend/reference_renderer.h"
#include "thinlod/frontend/view_camera.h"
