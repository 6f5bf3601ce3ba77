#include "noctua/place/keyframe_database.h"

#include <algorithm>

#include "noctua/util/error.h"

namespace noctua::place {

void DatabaseQueryOptions::Check() const {
  CheckOption(min_shared_words_ratio >= 0.0 && min_shared_words_ratio <= 1.0,
              "place: min_shared_words_ratio must be in [0, 1]");
  CheckOption(min_score_ratio >= 0.0 && min_score_ratio <= 1.0,
              "place: min_score_ratio must be in [0, 1]");
  CheckOption(covisibles >= 0, "place: covisibles must not be negative");
  CheckOption(max_candidates >= 0, "place: max_candidates must not be negative");
  CheckOption(min_score >= 0.0 && min_score <= 1.0, "place: min_score must be in [0, 1]");
}

void KeyFrameDatabase::Add(long id, BowVector bow, FeatureVector features) {
  Erase(id);
  for (const auto& [word, weight] : bow) {
    std::vector<long>& ids = inverted_[word];
    ids.insert(std::lower_bound(ids.begin(), ids.end(), id), id);
  }
  entries_[id] = Entry{std::move(bow), std::move(features)};
}

void KeyFrameDatabase::Erase(long id) {
  const auto it = entries_.find(id);
  if (it == entries_.end()) return;
  for (const auto& [word, weight] : it->second.bow) {
    std::vector<long>& ids = inverted_[word];
    const auto at = std::lower_bound(ids.begin(), ids.end(), id);
    if (at != ids.end() && *at == id) ids.erase(at);
    if (ids.empty()) inverted_.erase(word);
  }
  entries_.erase(it);
}

void KeyFrameDatabase::Clear() {
  entries_.clear();
  inverted_.clear();
}

std::vector<long> KeyFrameDatabase::Ids() const {
  std::vector<long> ids;
  for (const auto& [id, entry] : entries_) ids.push_back(id);
  return ids;
}

const BowVector& KeyFrameDatabase::bow(long id) const {
  const auto it = entries_.find(id);
  if (it == entries_.end())
    throw Error("place: keyframe " + std::to_string(id) + " is not in the database");
  return it->second.bow;
}

const FeatureVector& KeyFrameDatabase::features(long id) const {
  const auto it = entries_.find(id);
  if (it == entries_.end())
    throw Error("place: keyframe " + std::to_string(id) + " is not in the database");
  return it->second.features;
}

std::vector<PlaceCandidate> KeyFrameDatabase::Query(const BowVector& query,
                                                    const DatabaseQueryOptions& options,
                                                    const CovisiblesOf& covisibles,
                                                    const std::set<long>& excluded) const {
  options.Check();
  // Words shared with the query, per keyframe, from the inverted index.
  std::map<long, int> shared;
  for (const auto& [word, weight] : query) {
    const auto it = inverted_.find(word);
    if (it == inverted_.end()) continue;
    for (long id : it->second) {
      if (excluded.count(id) == 0) ++shared[id];
    }
  }
  int most_shared = 0;
  for (const auto& [id, count] : shared) most_shared = std::max(most_shared, count);
  if (most_shared == 0) return {};
  const double min_shared = options.min_shared_words_ratio * most_shared;
  std::map<long, PlaceCandidate> scored;
  for (const auto& [id, count] : shared) {
    if (count < min_shared) continue;
    PlaceCandidate candidate;
    candidate.id = id;
    candidate.shared_words = count;
    candidate.score = candidate.accumulated_score = Score(query, entries_.at(id).bow);
    if (candidate.score >= options.min_score) scored[id] = candidate;
  }
  // Each scored keyframe's group (itself and its scored covisibles) is represented by the
  // group's best keyframe (ties: the later one), with the group's total score.
  std::map<long, PlaceCandidate> groups;
  for (const auto& [id, candidate] : scored) {
    PlaceCandidate best = candidate;
    double total = candidate.score;
    if (covisibles && options.covisibles > 0) {
      for (long other : covisibles(id, options.covisibles)) {
        const auto it = scored.find(other);
        if (it == scored.end()) continue;
        total += it->second.score;
        const PlaceCandidate& member = it->second;
        if (member.score > best.score || (member.score == best.score && member.id > best.id)) {
          best = member;
        }
      }
    }
    best.accumulated_score = total;
    const auto existing = groups.find(best.id);
    if (existing == groups.end() || existing->second.accumulated_score < total) {
      groups[best.id] = best;
    }
  }
  double best_total = 0.0;
  for (const auto& [id, candidate] : groups) {
    best_total = std::max(best_total, candidate.accumulated_score);
  }
  std::vector<PlaceCandidate> result;
  for (const auto& [id, candidate] : groups) {
    if (candidate.accumulated_score >= options.min_score_ratio * best_total) {
      result.push_back(candidate);
    }
  }
  std::sort(result.begin(), result.end(), [](const PlaceCandidate& a, const PlaceCandidate& b) {
    if (a.accumulated_score != b.accumulated_score) {
      return a.accumulated_score > b.accumulated_score;
    }
    return a.id > b.id;
  });
  if (options.max_candidates > 0 && static_cast<int>(result.size()) > options.max_candidates) {
    result.resize(static_cast<std::size_t>(options.max_candidates));
  }
  return result;
}

}  // namespace noctua::place
