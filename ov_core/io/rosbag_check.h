#pragma once
// A ROS 1 bag's record structure checked before Debian's rosbag library opens it. The library takes record, header
// and chunk lengths from the file as they are and allocates them (up to 4 GiB for one damaged length field) before
// it finds that the file does not hold them; this walk (record lengths against the file, a chunk's uncompressed size
// against what a chunk can be, the records inside uncompressed chunks) turns such damage into an error naming the
// byte, before any allocation.
#include <string>

namespace ovton::core {

/// Walks the bag's records (format 2.0) from the magic to the end of the file. Throws DataError(file, "byte N: ...")
/// for a record whose lengths run past the file or its chunk, a chunk that declares an impossible size, or an index
/// position past the end.
void check_rosbag_structure(const std::string &file);

} // namespace ovton::core
