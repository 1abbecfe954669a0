// COLMAP's database (SQLite), read-only through SQLite's C API: image ids, descriptors, match counts.
#pragma once

#include <sqlite3.h>

#include <memory>
#include <string>

#include "core/error.h"

namespace weathergs::capture {

class ColmapDatabase {
 public:
  explicit ColmapDatabase(const std::string& path) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      throw InputError(path, "cannot open COLMAP's database: " + msg);
    }
  }
  ~ColmapDatabase() { sqlite3_close(db_); }
  ColmapDatabase(const ColmapDatabase&) = delete;
  ColmapDatabase& operator=(const ColmapDatabase&) = delete;

  // Runs `sql` and calls row(stmt) for each result row.
  template <typename F>
  void query(const char* sql, F&& row) const {
    sqlite3_stmt* raw = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &raw, nullptr) != SQLITE_OK)
      throw InputError(path_, std::string("cannot query COLMAP's database (") + sql + "): " + sqlite3_errmsg(db_));
    const std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)> stmt(raw, sqlite3_finalize);
    int rc;
    while ((rc = sqlite3_step(raw)) == SQLITE_ROW) row(raw);
    if (rc != SQLITE_DONE)
      throw InputError(path_, std::string("reading COLMAP's database (") + sql + ") failed: " + sqlite3_errmsg(db_));
  }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

}  // namespace weathergs::capture
