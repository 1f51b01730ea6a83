// Point caches: the positions of a fixed list of points, frame after frame, in the two formats
// DCC tools read (Blender's Mesh Cache modifier, 3ds Max, Maya, Houdini, LightWave). A cache
// moves the vertices of a mesh that has the same vertices in the same order (for softbody's
// export: the render meshes written by writeRenderMeshesObj with ObjObjects::One).
#pragma once

#include <string>
#include <vector>

#include "sim/base/file_io.h"
#include "sim/base/types.h"

namespace sb {

enum class PointCacheFormat {
  // PC2 ("Point Cache 2" of 3ds Max), little-endian: "POINTCACHE2\0" (12 bytes), int32 version
  // (1), int32 point count, float32 start frame, float32 sample rate (frames per sample: 1),
  // int32 sample count; then per sample every point as float32 x, y, z.
  Pc2,
  // MDD (LightWave), big-endian: int32 frame count, int32 point count, float32 time of each
  // frame (s); then per frame every point as float32 x, y, z.
  Mdd,
};

// Writes one cache. Frame k is at time startTime + k · frameInterval (s); the start frame of a
// PC2 is startTime / frameInterval, so frame numbers count frameIntervals from time 0. Both
// formats hold the frame count in front of the data, so it is given up front and finish()
// checks it. The file appears at `path` only on finish() (sim/base/file_io.h: atomic); a writer
// destroyed before that removes what it wrote. Positions in metres, as float32 (the world's
// precision: nothing is rounded).
class PointCacheWriter {
 public:
  // pointCount ≥ 1, frameCount ≥ 1, frameInterval > 0 and finite; throws std::invalid_argument
  // otherwise, FileError when the file cannot be created.
  PointCacheWriter(const std::string& path, PointCacheFormat format, int pointCount, int frameCount,
                   double startTime, double frameInterval);

  // Appends the next frame: the rows of `parts`, in order, are the points (their row counts add
  // up to pointCount, else std::invalid_argument and nothing is written). Throws FileError on a
  // write error and std::logic_error past the declared frame count.
  void addFrame(const std::vector<PointsRowMajor>& parts);

  // Publishes the cache. Throws std::logic_error when fewer frames than declared were added
  // (nothing is published), FileError when the file cannot be written.
  void finish();

  int framesWritten() const { return written_; }

 private:
  AtomicFileWriter file_;
  PointCacheFormat format_;
  int pointCount_;
  int frameCount_;
  int written_ = 0;
  std::vector<char> buffer_;  // one frame in the file's byte order
};

}  // namespace sb
