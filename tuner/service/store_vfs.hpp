#pragma once
// The SQLite VFS the job store opens its database with: the platform's own, passed through, with
// the test seam of inject_store_full() (job_store.hpp) on its writes. Private to tuner/service.

namespace ftc::tune::service_detail {

// Registers the VFS on first use; returns its name for sqlite3_open_v2.
const char* store_vfs();

}  // namespace ftc::tune::service_detail
