// Private to the trace area: the SQLite3 storage of rosbag2 (tables topics and messages), read by
// rosbag.cpp for .db3 files.
#pragma once

#include <filesystem>
#include <functional>

#include "tripodal/trace/rosbag.hpp"

namespace tripodal::trace::detail {

/// Every row of table messages, by time stamp then row id, with its topic from table topics.
/// Throws BagFormatError naming the file and the table or row; TraceIoError when unreadable.
void for_each_db3_message(const std::filesystem::path& file, const std::function<void(const BagMessage&)>& visit,
                          BagImportReport& report);

}  // namespace tripodal::trace::detail
