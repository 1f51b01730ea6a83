// Undo for the body parameters edited in the panel (Ctrl+Z), and "reset parameters to the
// file's": the parameters every body had when the scene was opened or last saved.
#include "app/viewer_app.h"

namespace sb::app {

namespace {

// Every field of BodyParams (it has no operator==; padding rules out memcmp).
bool sameParams(const BodyParams& a, const BodyParams& b) {
  return a.mode == b.mode && a.alpha == b.alpha && a.beta == b.beta &&
         a.preserveVolume == b.preserveVolume && a.damping == b.damping &&
         a.restitution == b.restitution && a.plasticity.yield == b.plasticity.yield &&
         a.plasticity.creep == b.plasticity.creep && a.plasticity.max == b.plasticity.max;
}

}  // namespace

void ViewerApp::rememberFileParams() {
  fileParams_.clear();
  for (const SceneBody& b : scene_.bodies)
    fileParams_.push_back({b.handle, scene_.world.params(b.handle)});
}

const BodyParams* ViewerApp::fileParamsOf(BodyHandle body) const {
  for (const ParamEdit& e : fileParams_)
    if (e.body == body) return &e.before;
  return nullptr;
}

void ViewerApp::rememberParamEdit(BodyHandle body, const BodyParams& before) {
  if (!paramUndo_.empty() && paramUndo_.back().body == body &&
      sameParams(paramUndo_.back().before, before))
    return;  // a second control touched without a change in between: one step back is enough
  paramUndo_.push_back({body, before});
  if (paramUndo_.size() > kMaxParamUndo) paramUndo_.erase(paramUndo_.begin());
}

void ViewerApp::setBodyParams(BodyHandle body, const BodyParams& params) {
  try {
    scene_.world.setParams(body, params);
  } catch (const std::exception& e) {
    errorMessage_ = scene_.world.name(body) + ": " + e.what();
  }
}

void ViewerApp::undoParamEdit() {
  // The newest entry that still changes something (a control clicked without a change leaves
  // an entry equal to the present parameters; a removed body's entries are dropped).
  while (!paramUndo_.empty()) {
    const ParamEdit e = paramUndo_.back();
    paramUndo_.pop_back();
    if (!scene_.world.contains(e.body)) continue;
    if (sameParams(scene_.world.params(e.body), e.before)) continue;
    setBodyParams(e.body, e.before);
    statusMessage_ = "undid a parameter change of " + scene_.world.name(e.body);
    return;
  }
  statusMessage_ = "nothing to undo";
}

void ViewerApp::resetParamsToFile(BodyHandle body) {
  const BodyParams* file = fileParamsOf(body);
  if (!file) return;
  const BodyParams now = scene_.world.params(body);
  if (sameParams(now, *file)) return;
  rememberParamEdit(body, now);
  setBodyParams(body, *file);
  statusMessage_ = "parameters of " + scene_.world.name(body) + " reset to the file's";
}

}  // namespace sb::app
