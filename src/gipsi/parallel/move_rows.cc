/// @file
/// MoveRows: per-item rows from wherever they are to the ranks that hold their items, through
/// each item's block rank.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/mesh_partition_detail.h"

namespace gipsi {

MovedRows MoveRows(std::span<const int> held, std::int64_t count, std::span<const int> whole,
                   std::span<const double> rows, int width, MPI_Comm comm) {
  GIPSI_CHECK(width > 0 && rows.size() == whole.size() * static_cast<std::size_t>(width),
              "MoveRows: {} values for {} rows of {}", rows.size(), whole.size(), width);
  const std::int64_t nodes = count;  // items of any kind: "node" below
  int size = 1, rank = 0;
  MPI_Comm_size(comm, &size);
  MPI_Comm_rank(comm, &rank);
  if (count == 0) {  // no items of this kind anywhere
    GIPSI_CHECK(held.empty() && whole.empty(), "MoveRows: items of an empty kind");
    return {};
  }
  const auto w = static_cast<std::size_t>(width);
  const auto record = w + 1;           // the node's whole index (exact in a double), then the row
  std::int64_t counts[3] = {0, 0, 0};  // missing, repeated, outside
  int first_missing = std::numeric_limits<int>::max();

  // 1. Every rank tells each of its items' block rank that it holds the item.
  std::vector<std::vector<int>> asks(static_cast<std::size_t>(size));
  for (const int n : held)
    asks[static_cast<std::size_t>(detail::BlockRank(n, nodes, size))].push_back(n);
  const detail::Received<int> holders = detail::Exchange(asks, comm);
  asks = {};

  // 2. The rows go to their nodes' block ranks.
  std::vector<std::vector<double>> to(static_cast<std::size_t>(size));
  for (std::size_t j = 0; j < whole.size(); ++j) {
    if (whole[j] < 0 || whole[j] >= nodes) {
      ++counts[2];
      continue;
    }
    auto& out = to[static_cast<std::size_t>(detail::BlockRank(whole[j], nodes, size))];
    out.push_back(static_cast<double>(whole[j]));
    out.insert(out.end(), rows.begin() + static_cast<std::ptrdiff_t>(j * w),
               rows.begin() + static_cast<std::ptrdiff_t>((j + 1) * w));
  }
  detail::Received<double> arrived = detail::Exchange(to, comm);
  to.assign(static_cast<std::size_t>(size), {});

  // 3. The block rank keeps where each of its nodes' row is, then forwards it to every holder.
  const std::int64_t begin = BlockBegin(nodes, rank, size);
  const std::int64_t block = BlockBegin(nodes, rank + 1, size) - begin;
  std::vector<std::int64_t> row_at(static_cast<std::size_t>(block), -1);
  for (std::size_t at = 0; at < arrived.items.size(); at += record) {
    const auto n = static_cast<std::int64_t>(arrived.items[at]);
    std::int64_t& slot = row_at[static_cast<std::size_t>(n - begin)];
    if (slot >= 0)
      ++counts[1];
    else
      slot = static_cast<std::int64_t>(at);
  }
  std::size_t from = 0;
  for (int r = 0; r < size; ++r) {
    const auto asked = static_cast<std::size_t>(holders.counts[static_cast<std::size_t>(r)]);
    for (std::size_t k = from; k < from + asked; ++k) {
      const int n = holders.items[k];
      const std::int64_t at = row_at[static_cast<std::size_t>(n - begin)];
      if (at < 0) {
        ++counts[0];
        first_missing = std::min(first_missing, n);
        continue;
      }
      auto& out = to[static_cast<std::size_t>(r)];
      const auto* row = arrived.items.data() + at;
      out.insert(out.end(), row, row + record);
    }
    from += asked;
  }
  arrived = {};
  const detail::Received<double> mine = detail::Exchange(to, comm);
  to = {};

  // 4. Each rank puts its rows in the order of its items.
  std::vector<std::pair<int, int>> local_of;  // (whole index, local index)
  local_of.reserve(held.size());
  for (std::size_t i = 0; i < held.size(); ++i) local_of.emplace_back(held[i], static_cast<int>(i));
  std::sort(local_of.begin(), local_of.end());
  MovedRows moved;
  moved.rows.assign(held.size() * w, 0.0);
  for (std::size_t at = 0; at < mine.items.size(); at += record) {
    const auto n = static_cast<int>(mine.items[at]);
    const auto it = std::lower_bound(local_of.begin(), local_of.end(), std::make_pair(n, -1));
    GIPSI_CHECK(it != local_of.end() && it->first == n,
                "MoveRows: a row for item {} came to a "
                "rank without it",
                n);
    std::copy_n(mine.items.data() + at + 1, w,
                moved.rows.data() + static_cast<std::size_t>(it->second) * w);
  }

  MPI_Allreduce(MPI_IN_PLACE, counts, 3, MPI_INT64_T, MPI_SUM, comm);
  MPI_Allreduce(MPI_IN_PLACE, &first_missing, 1, MPI_INT, MPI_MIN, comm);
  moved.missing = counts[0];
  moved.repeated = counts[1];
  moved.outside = counts[2];
  moved.first_missing = counts[0] > 0 ? first_missing : -1;
  return moved;
}

}  // namespace gipsi
