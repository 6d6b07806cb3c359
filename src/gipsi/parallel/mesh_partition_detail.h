#pragma once
/// @file
/// Internal to the partitioner (mesh_partition.cc, mesh_partition_blocks.cc): the all-to-all
/// exchange of plain records, the block rank of an item, and the PT-Scotch call.

#include <mpi.h>

#include <array>
#include <cstdint>
#include <numeric>
#include <type_traits>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/geometry/mesh_block.h"

namespace gipsi::detail {

/// What an exchange delivered: the items, from rank 0's first, and how many came from each rank.
template <class T>
struct Received {
  std::vector<T> items;
  std::vector<int> counts;
};

/// Sends `to[r]` to rank r and receives what every rank sent here. Collective. T is a plain
/// record (copied as bytes, so only between processes of one build).
template <class T>
Received<T> Exchange(const std::vector<std::vector<T>>& to, MPI_Comm comm) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<int> send_counts(to.size()), send_offsets(to.size(), 0),
      receive_offsets(to.size(), 0);
  Received<T> out;
  out.counts.resize(to.size());
  std::int64_t total_sent = 0;
  for (std::size_t r = 0; r < to.size(); ++r) {
    GIPSI_CHECK(to[r].size() < static_cast<std::size_t>(1) << 31, "an exchange past 2^31 records");
    send_counts[r] = static_cast<int>(to[r].size());
    total_sent += send_counts[r];
  }
  GIPSI_CHECK(total_sent < std::int64_t{1} << 31, "an exchange past 2^31 records");
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, out.counts.data(), 1, MPI_INT, comm);
  std::partial_sum(send_counts.begin(), send_counts.end() - 1, send_offsets.begin() + 1);
  std::int64_t total = 0;
  for (int c : out.counts) total += c;
  GIPSI_CHECK(total < std::int64_t{1} << 31, "an exchange past 2^31 records");
  std::partial_sum(out.counts.begin(), out.counts.end() - 1, receive_offsets.begin() + 1);
  std::vector<T> send;
  send.reserve(static_cast<std::size_t>(total_sent));
  for (const auto& part : to) send.insert(send.end(), part.begin(), part.end());
  out.items.resize(static_cast<std::size_t>(total));
  MPI_Datatype record = MPI_DATATYPE_NULL;
  MPI_Type_contiguous(static_cast<int>(sizeof(T)), MPI_BYTE, &record);
  MPI_Type_commit(&record);
  MPI_Alltoallv(send.data(), send_counts.data(), send_offsets.data(), record, out.items.data(),
                out.counts.data(), receive_offsets.data(), record, comm);
  MPI_Type_free(&record);
  return out;
}

/// The rank a face's records meet on: a hash of its sorted nodes (splitmix64's finaliser).
inline int FaceRank(const std::array<int, 3>& f, int size) {
  std::uint64_t h = 0x9E3779B97F4A7C15ULL;
  for (int n : f) {
    h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(n)) + 0x9E3779B97F4A7C15ULL +
         (h << 6) + (h >> 2);
    h ^= h >> 30;
    h *= 0xBF58476D1CE4E5B9ULL;
    h ^= h >> 27;
    h *= 0x94D049BB133111EBULL;
    h ^= h >> 31;
  }
  return static_cast<int>(h % static_cast<std::uint64_t>(size));
}

/// The rank whose block (BlockBegin) holds item `item` of `count` split over `size` ranks.
inline int BlockRank(std::int64_t item, std::int64_t count, int size) {
  auto rank = static_cast<int>(item * size / count);
  while (rank > 0 && BlockBegin(count, rank, size) > item) --rank;
  while (rank + 1 < size && BlockBegin(count, rank + 1, size) <= item) ++rank;
  return rank;
}

/// The part of every tet of this rank's block: PT-Scotch on the dual graph whose rows this
/// rank gives (`rows`: CSR offsets, `columns`: whole-mesh tet indices), in its deterministic
/// mode with a fixed seed, balanced by tet count. Collective. On one rank every tet is in part 0.
/// Throws std::runtime_error if PT-Scotch fails.
std::vector<int> ScotchPart(const std::vector<int>& rows, std::vector<int>& columns, MPI_Comm comm,
                            int size);

}  // namespace gipsi::detail
