#pragma once

#include <functional>
#include <map>
#include <set>
#include <vector>

#include "noctua/place/vocabulary.h"

namespace noctua::place {

struct DatabaseQueryOptions {
  // Candidates must share at least this fraction of the words that the keyframe sharing the most
  // words with the query shares (ORB-SLAM: 0.8).
  double min_shared_words_ratio = 0.8;
  // Candidates whose (accumulated) score is below this fraction of the best are dropped
  // (ORB-SLAM: 0.75).
  double min_score_ratio = 0.75;
  // Covisible keyframes of each candidate (see KeyFrameDatabase::Query) whose scores add to its
  // own, so that a place seen by several keyframes outranks a lone lookalike (ORB-SLAM: 10).
  int covisibles = 10;
  int max_candidates = 0;  // 0: all that pass
  // Keyframes scoring below this are no candidates and add nothing to a group's score (ORB-SLAM's
  // loop detection: the lowest score of the query keyframe's covisibles; relocalisation: 0).
  double min_score = 0.0;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

struct PlaceCandidate {
  long id = 0;
  double score = 0.0;              // Score(query, its BowVector)
  double accumulated_score = 0.0;  // with its covisible keyframes' scores (== score without)
  int shared_words = 0;
};

// Keyframes (by id) with their bag of words and direct index, and the inverted index word ->
// keyframes that finds the ones sharing words with a query without scoring every keyframe.
class KeyFrameDatabase {
 public:
  // Replaces an entry of the same id.
  void Add(long id, BowVector bow, FeatureVector features);
  void Erase(long id);
  bool Contains(long id) const { return entries_.count(id) > 0; }
  int size() const { return static_cast<int>(entries_.size()); }
  void Clear();
  std::vector<long> Ids() const;  // in increasing order
  // Throw noctua::Error for an id not in the database.
  const BowVector& bow(long id) const;
  const FeatureVector& features(long id) const;

  // Keyframes that look like the query, best first (ties: the higher id), filtered as ORB-SLAM's
  // relocalisation does: only keyframes sharing enough words are scored; with `covisibles`
  // (id -> its covisible keyframes, best first) each candidate's score accumulates over those of
  // its best covisibles that were scored too, and the group is represented by its best-scoring
  // keyframe. Keyframes in `excluded` are left out before anything is counted (loop detection:
  // the query keyframe and those covisible with it). Deterministic: the same database and query
  // give the same list.
  using CovisiblesOf = std::function<std::vector<long>(long id, int count)>;
  std::vector<PlaceCandidate> Query(const BowVector& query, const DatabaseQueryOptions& options,
                                    const CovisiblesOf& covisibles = {},
                                    const std::set<long>& excluded = {}) const;

 private:
  struct Entry {
    BowVector bow;
    FeatureVector features;
  };
  std::map<long, Entry> entries_;
  std::map<int, std::vector<long>> inverted_;  // word -> ids holding it, increasing
};

}  // namespace noctua::place
