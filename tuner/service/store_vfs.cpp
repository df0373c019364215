#include "service/store_vfs.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <stdexcept>

#include "ftc/tune/service/job_store.hpp"

namespace ftc::tune {

namespace {

// inject_store_full(): 0 = off; n > 0 = the n-th write counted from the call fails, and every
// later one, as on a disk that has filled up.
std::atomic<long> g_full_after{0};
std::atomic<long> g_writes{0};

bool write_refused() {
  const long after = g_full_after.load();
  return after > 0 && ++g_writes >= after;
}

sqlite3_vfs* g_real = nullptr;
sqlite3_vfs g_vfs;
// One method table per version of the wrapped file's own (a file must not be offered methods
// its real implementation lacks).
sqlite3_io_methods g_methods[4];

// A file of this VFS: the header SQLite sees, then the platform VFS's file in the same block.
struct File {
  sqlite3_file base;
  sqlite3_file* real;
};
sqlite3_file* real(sqlite3_file* f) { return reinterpret_cast<File*>(f)->real; }
const sqlite3_io_methods& m(sqlite3_file* f) { return *real(f)->pMethods; }

int x_close(sqlite3_file* f) { return m(f).xClose(real(f)); }
int x_read(sqlite3_file* f, void* buf, int n, sqlite3_int64 off) {
  return m(f).xRead(real(f), buf, n, off);
}
int x_write(sqlite3_file* f, const void* buf, int n, sqlite3_int64 off) {
  if (write_refused()) return SQLITE_FULL;
  return m(f).xWrite(real(f), buf, n, off);
}
int x_truncate(sqlite3_file* f, sqlite3_int64 size) { return m(f).xTruncate(real(f), size); }
int x_sync(sqlite3_file* f, int flags) { return m(f).xSync(real(f), flags); }
int x_file_size(sqlite3_file* f, sqlite3_int64* size) { return m(f).xFileSize(real(f), size); }
int x_lock(sqlite3_file* f, int level) { return m(f).xLock(real(f), level); }
int x_unlock(sqlite3_file* f, int level) { return m(f).xUnlock(real(f), level); }
int x_check_reserved_lock(sqlite3_file* f, int* out) {
  return m(f).xCheckReservedLock(real(f), out);
}
int x_file_control(sqlite3_file* f, int op, void* arg) {
  return m(f).xFileControl(real(f), op, arg);
}
int x_sector_size(sqlite3_file* f) { return m(f).xSectorSize(real(f)); }
int x_device_characteristics(sqlite3_file* f) { return m(f).xDeviceCharacteristics(real(f)); }
int x_shm_map(sqlite3_file* f, int region, int size, int extend, void volatile** out) {
  return m(f).xShmMap(real(f), region, size, extend, out);
}
int x_shm_lock(sqlite3_file* f, int offset, int n, int flags) {
  return m(f).xShmLock(real(f), offset, n, flags);
}
void x_shm_barrier(sqlite3_file* f) { m(f).xShmBarrier(real(f)); }
int x_shm_unmap(sqlite3_file* f, int remove) { return m(f).xShmUnmap(real(f), remove); }
int x_fetch(sqlite3_file* f, sqlite3_int64 off, int n, void** out) {
  return m(f).xFetch(real(f), off, n, out);
}
int x_unfetch(sqlite3_file* f, sqlite3_int64 off, void* p) {
  return m(f).xUnfetch(real(f), off, p);
}

int x_open(sqlite3_vfs*, sqlite3_filename name, sqlite3_file* f, int flags, int* out_flags) {
  File* file = reinterpret_cast<File*>(f);
  file->real = reinterpret_cast<sqlite3_file*>(file + 1);
  file->real->pMethods = nullptr;
  const int rc = g_real->xOpen(g_real, name, file->real, flags, out_flags);
  // SQLite closes a file whose pMethods is set, even after a failed open.
  file->base.pMethods =
      file->real->pMethods ? &g_methods[std::clamp(file->real->pMethods->iVersion, 1, 3)] : nullptr;
  return rc;
}
int x_delete(sqlite3_vfs*, const char* name, int sync_dir) {
  return g_real->xDelete(g_real, name, sync_dir);
}
int x_access(sqlite3_vfs*, const char* name, int flags, int* out) {
  return g_real->xAccess(g_real, name, flags, out);
}
int x_full_pathname(sqlite3_vfs*, const char* name, int n, char* out) {
  return g_real->xFullPathname(g_real, name, n, out);
}

void register_vfs() {
  g_real = sqlite3_vfs_find(nullptr);
  if (g_real == nullptr) throw std::runtime_error("job store: SQLite has no default VFS");
  for (int v = 1; v <= 3; ++v) {
    g_methods[v] = sqlite3_io_methods{v,
                                      x_close,
                                      x_read,
                                      x_write,
                                      x_truncate,
                                      x_sync,
                                      x_file_size,
                                      x_lock,
                                      x_unlock,
                                      x_check_reserved_lock,
                                      x_file_control,
                                      x_sector_size,
                                      x_device_characteristics,
                                      v >= 2 ? x_shm_map : nullptr,
                                      v >= 2 ? x_shm_lock : nullptr,
                                      v >= 2 ? x_shm_barrier : nullptr,
                                      v >= 2 ? x_shm_unmap : nullptr,
                                      v >= 3 ? x_fetch : nullptr,
                                      v >= 3 ? x_unfetch : nullptr};
  }
  // The platform's methods for everything but files (randomness, time, dlopen...).
  g_vfs = *g_real;
  g_vfs.pNext = nullptr;
  g_vfs.zName = "ftctune-store";
  g_vfs.szOsFile = static_cast<int>(sizeof(File)) + g_real->szOsFile;
  g_vfs.xOpen = x_open;
  g_vfs.xDelete = x_delete;
  g_vfs.xAccess = x_access;
  g_vfs.xFullPathname = x_full_pathname;
  if (sqlite3_vfs_register(&g_vfs, 0) != SQLITE_OK)
    throw std::runtime_error("job store: cannot register its SQLite VFS");
}

}  // namespace

void inject_store_full(int after) {
  g_writes = 0;
  g_full_after = after;
}

namespace service_detail {

const char* store_vfs() {
  static std::once_flag once;
  std::call_once(once, register_vfs);
  return g_vfs.zName;
}

}  // namespace service_detail

}  // namespace ftc::tune
