// Switching how a body's render mesh follows its cage while the scene runs (the viewer's
// "embedding" control): the render mesh is bound again with another method and replaces the
// old binding only once the bind has succeeded, so a refused or failing bind leaves the body
// exactly as it was.
#pragma once

#include "sim/cage/bind.h"
#include "sim/scene/scene.h"

namespace sb {

// Binds body `body`'s render mesh (re-read from its file) to the body's cage (its start
// positions, World::restPositions, taken back to the file's coordinates through the body's
// placement, where a scene load binds too) with `method`, then sets both the body's
// RenderMesh::embedding and SceneBody::embedding to it, so renderVertices and saving follow.
// Render meshes shared with other bodies (the scene binds a mesh–cage pair once) are not
// touched: the body gets a RenderMesh of its own. `options`: threads, cache folder, progress
// (the bind's; the default binds on every core without a cache).
//
// Throws, with the scene unchanged: std::out_of_range for a body index outside the scene;
// std::invalid_argument for a body without a render mesh or a lattice body (its mesh follows
// the lattice's nodes, not a cage) and for an option outside the scene file's ranges (scene.h,
// checked before any binding); whatever mesh::readMesh and cage::bindToCage throw (a method the
// cage library does not bind for cages, a cage it refuses).
void rebindRenderMesh(Scene& scene, int body, const cage::EmbeddingMethod& method,
                      const cage::BindOptions& options = {});

// Whether `a` and `b` bind the same way: the same kind and, for that kind, the same options.
bool sameEmbeddingMethod(const cage::EmbeddingMethod& a, const cage::EmbeddingMethod& b);

}  // namespace sb
