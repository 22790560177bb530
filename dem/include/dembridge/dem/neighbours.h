#pragma once
/// @file neighbours.h
/// Cell-list neighbour search with a skin (a service the force loop asks for).
/// Pairs (a < b, sorted) whose gap is below the skin carry a contact history
/// (shear force) that survives rebuilds. A sphere that has moved more than
/// 0.3 skin since it was last searched is searched again (its pairs are
/// replaced); the whole list is rebuilt when many have.

#include "dembridge/dem/assembly.h"
#include "dembridge/core/checkpoint.h"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace dembridge::dem
{

/// Uniform grid of cubic cells over a bounding box; each cell lists the
/// particles whose centre lies in it.
class CellGrid
{
public:
  /// @param x centres (n, 3); @param cell cell edge [m] (>= the search range);
  /// @param skip one flag per particle (or empty): flagged ones are left
  /// out (and do not stretch the grid's bounds)
  CellGrid(std::span<const double> x, double cell, std::span<const std::uint8_t> skip = {});
  /// Calls fn(k0, k1) for the 9 runs [k0, k1) of items() that hold the 27
  /// cells around point p (cells are numbered z fastest, so the three cells
  /// along z of a column are one run).
  template <typename Fn>
  void for_each_run_near(const double* p, Fn&& fn) const
  {
    int c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = cell_of(p[k], k);
    const int z0 = std::max(c[2] - 1, 0), z1 = std::min(c[2] + 1, _n[2] - 1);
    for (int i = std::max(c[0] - 1, 0); i <= std::min(c[0] + 1, _n[0] - 1); ++i)
      for (int j = std::max(c[1] - 1, 0); j <= std::min(c[1] + 1, _n[1] - 1); ++j)
      {
        const std::size_t row = (std::size_t(i) * _n[1] + j) * _n[2];
        fn(_start[row + z0], _start[row + z1 + 1]);
      }
  }
  /// Calls fn(j) for every particle j in the 27 cells around point p.
  template <typename Fn>
  void for_each_near(const double* p, Fn&& fn) const
  {
    for_each_run_near(p,
                      [&](std::int32_t k0, std::int32_t k1)
                      {
                        for (std::int32_t q = k0; q < k1; ++q)
                          fn(_items[q]);
                      });
  }
  /// The particles in cell order.
  const std::vector<std::int32_t>& items() const { return _items; }
  /// Calls fn(j) for every particle j in the cells that overlap the box
  /// [lo, hi] (clamped to the grid: points outside it lie in its edge cells).
  template <typename Fn>
  void for_each_in_box(const double* lo, const double* hi, Fn&& fn) const
  {
    int c0[3], c1[3];
    for (int k = 0; k < 3; ++k)
    {
      if (hi[k] < _lo[k] - _h || lo[k] > _lo[k] + (_n[k] + 1) * _h)
        return; // the box misses the grid
      c0[k] = cell_of(lo[k], k);
      c1[k] = cell_of(hi[k], k);
    }
    for (int i = c0[0]; i <= c1[0]; ++i)
      for (int j = c0[1]; j <= c1[1]; ++j)
      {
        const std::size_t row = (std::size_t(i) * _n[1] + j) * _n[2];
        for (std::int32_t q = _start[row + c0[2]]; q < _start[row + c1[2] + 1]; ++q)
          fn(_items[q]);
      }
  }
  std::size_t bytes() const { return (_start.capacity() + _items.capacity()) * sizeof(std::int32_t); }
  /// The edge of a cell [m] (the requested size, or more for a spread-out set).
  double cell_size() const { return _h; }

  /// Calls fn(j, d2) for every particle j > i near particle i (same 27
  /// cells), with d2 the squared centre distance; x is the array the grid
  /// was built from.
  template <typename Fn>
  void for_each_later_near(std::span<const double> x, std::size_t i, Fn&& fn) const
  {
    for_each_near(&x[3 * i],
                  [&](std::int32_t j)
                  {
                    if (j <= static_cast<std::int32_t>(i))
                      return;
                    const double dx = x[3 * j] - x[3 * i], dy = x[3 * j + 1] - x[3 * i + 1],
                                 dz = x[3 * j + 2] - x[3 * i + 2];
                    fn(j, dx * dx + dy * dy + dz * dz);
                  });
  }

private:
  int cell_of(double v, int k) const;
  double _lo[3], _h;
  int _n[3];
  std::vector<std::int32_t> _start, _items;
};

class NeighbourList
{
public:
  /// @param skin extra search distance beyond contact [m], > 0
  explicit NeighbourList(double skin);

  /// Brings the list up to date: the spheres that moved more than
  /// `mover_share` x skin since they were last searched (the movers) are
  /// searched again, their pairs replaced; the whole list is rebuilt on the
  /// first call (a remove() before it included) or when the movers are
  /// more than an eighth of the spheres; spheres remove()d since the last
  /// call lose their pairs here. Returns true if the list
  /// changed.
  ///
  /// Why it stays complete: a pair left out had a gap of at least a skin
  /// when the later of its two spheres was searched. Since then that sphere
  /// has moved at most 0.3 skin and the other at most 0.6 (0.3 from where it
  /// was searched, to then and to now), so the gap is still 0.1 skin.
  ///
  /// Pairs joined by an intact link are left out (the link acts there); a
  /// pair whose link is broken is listed, with its link index, like any
  /// other.
  ///
  /// With `defer`, a search of the movers alone keeps their new pairs aside:
  /// the list changes at the next add_broken_links(), which merges them with
  /// the pairs of the links broken in between, in one pass over the list
  /// (the force loop breaks links between the two calls). The list is the
  /// same as with two merges; it is out of date between the two calls.
  bool update(std::span<const double> x, std::span<const double> r, const Links& links,
              std::span<const std::uint8_t> skip = {}, bool defer = false);
  /// How far a sphere searched again moves from where it was searched [skin].
  static constexpr double mover_share = 0.3;
  /// Spheres removed from the computation (`gone`): the next update() drops
  /// their pairs in the merge of its search (as a mover's pairs are
  /// replaced; a search of no sphere if none moved) and makes the grid
  /// without them; the other pairs and their histories stay, and the list
  /// is not rebuilt. `skip` flags every sphere removed so far, `gone`
  /// included: the searches leave them out from now on. Call update() (with
  /// the same `skip`) before anything reads the pairs or grid(): until then
  /// the list still holds the removed spheres' pairs. x: the positions now
  /// (their count sizes the flags).
  void remove(std::span<const double> x, std::span<const std::int32_t> gone, std::span<const std::uint8_t> skip);

  /// Adds the pairs of links that have just broken (sorted by link index,
  /// hence by (a, b)), with no contact history, so a contact can take over
  /// within the same step; pairs already listed are skipped. Merges a
  /// deferred search's pairs too (update()), even when `ids` is empty.
  void add_broken_links(const Links& links, std::span<const std::int32_t> ids);
  /// A deferred search waits for add_broken_links().
  bool pending() const { return _pending; }

  std::size_t size() const { return a.size(); }
  std::size_t builds() const { return _builds; }
  /// Changes whenever the list of pairs changes (rebuild, added pairs,
  /// removed spheres).
  std::size_t version() const { return _version; }
  double skin() const { return _skin; }
  /// The cell grid of the last change (null before the first), over the
  /// positions then; spheres have moved less than drift() since.
  const CellGrid* grid() const { return _grid ? &*_grid : nullptr; }
  /// The most a sphere moves from where grid() has it, or between two
  /// changes of the list [m]: twice mover_share x skin.
  double drift() const { return 2.0 * mover_share * _skin; }
  /// The searches of movers alone (builds() counts every search).
  std::size_t partial_builds() const { return _partial; }
  /// Bytes held by the list.
  std::size_t bytes() const;
  /// From now on the list keeps a rolling moment per pair (mr, zero for the
  /// pairs listed so far), carried through its changes like fs.
  void keep_rolling();
  bool rolling() const { return _rolling; }
  /// From the next search on the list also keeps each pair of a broken
  /// link while its distance is below R_a + R_b + c (D_init - R_a - R_b)
  /// plus the skin (Material::crack_closure = c in (0, 1]: such a pair
  /// touches again from there). The search then reaches that much farther
  /// for every sphere.
  void close_cracks(double c);
  double closing_cracks() const { return _closure; }
  /// The pairs, their contact history and the build state, to a checkpoint.
  void save(const checkpoint::Group& g) const;
  /// Reads what save() wrote (the skin must be the same).
  void load(const checkpoint::Group& g);

  std::vector<std::int32_t> a, b;  ///< pairs, a < b, sorted
  std::vector<std::int32_t> link;  ///< index of the pair's (broken) link, or -1; never an intact one
  std::vector<double> fs;          ///< contact shear force on b, (pairs, 3) [N]
  /// contact rolling moment on b, (pairs, 3) [N m]; empty until
  /// keep_rolling() (Material::rolling_friction)
  std::vector<double> mr;
  std::vector<double> n;           ///< contact normal at the last step, (pairs, 3)
  std::vector<std::uint8_t> touching; ///< 1 while the pair is in contact

private:
  void build(std::span<const double> x, std::span<const double> r, const Links& links,
             std::span<const std::uint8_t> skip);
  void search_movers(std::span<const double> x, std::span<const double> r, const Links& links,
                     const std::vector<std::int32_t>& movers, bool defer);
  void merge(std::span<const std::int32_t> na, std::span<const std::int32_t> nb,
             std::span<const std::int32_t> nlink, std::span<const std::uint8_t> moving, bool replace_all);
  /// The list's columns, as a merge writes them.
  struct Columns
  {
    std::vector<std::int32_t> a, b, link;
    std::vector<double> fs, mr, n;
    std::vector<std::uint8_t> touching;
    /// m pairs (mr only with rolling moments); growth zero-filled, the rest kept
    void resize(std::size_t m, bool rolling)
    {
      a.resize(m);
      b.resize(m);
      link.resize(m);
      fs.resize(3 * m);
      mr.resize(rolling ? 3 * m : 0);
      n.resize(3 * m);
      touching.resize(m);
    }
  };
  void copy_pairs(std::size_t q0, std::size_t q1, Columns& out, std::size_t o) const;
  /// One chunk of a merge (neighbours.cpp): the listed pairs [q0, q1) and the
  /// new pairs [p0, p1) that go among them, written into out from slot o, or
  /// with out null only counted; returns the count.
  std::size_t merge_chunk(std::size_t q0, std::size_t q1, std::span<const std::int32_t> na,
                          std::span<const std::int32_t> nb, std::span<const std::int32_t> nlink,
                          std::size_t p0, std::size_t p1, std::span<const std::uint8_t> moving,
                          bool replace_all, Columns* out, std::size_t o) const;
  std::size_t first_at_or_after(std::size_t q, std::size_t end, std::int32_t i, std::int32_t j) const;
  void end_search();
  double _skin;
  std::size_t _builds = 0, _version = 0, _partial = 0;
  std::vector<double> _x_build;    // where each sphere was last searched
  std::vector<double> _x_grid;     // the positions the grid was made from
  double _cell = 0.0;              // the grid's cell size at the last build
  bool _stale = false;             // rebuild at the next update
  bool _rolling = false;           // mr is kept
  double _closure = 0.0;           // c: broken links' pairs kept to R_a + R_b + c (D_init - R_a - R_b) + skin
  double _reach = 0.0;             // the most c (D_init - R_a - R_b) of a link (with _closure) [m]
  bool _reach_known = false;
  double reach(std::span<const double> r, const Links& links);
  /// A pair at squared distance d2 within the list's reach: gap below the skin,
  /// from R_a + R_b, or with _closure from a broken link's closing distance.
  bool keeps(double d2, double rs, const Links& links, std::int32_t k) const;
  // the columns a merge writes into, then swaps with the list's: the list's
  // previous columns, kept so that a merge neither allocates nor clears
  Columns _spare;
  std::vector<std::uint8_t> _skip; // the spheres left out of the searches (removed)
  std::optional<CellGrid> _grid;
  // the movers of the last search (flag per sphere, cleared by end_search)
  std::vector<std::uint8_t> _moving;
  std::vector<std::int32_t> _movers;
  // the spheres removed since the last search (flagged in _moving too):
  // their pairs go at the next merge
  std::vector<std::int32_t> _dropped;
  // a deferred search's new pairs, sorted by (a, b)
  std::vector<std::int32_t> _pend_a, _pend_b, _pend_link;
  bool _pending = false;
};

} // namespace dembridge::dem
