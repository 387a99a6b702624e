#pragma once

/// A minimal data-oriented ECS: entities are integer ids, each component type lives in one
/// sparse-set pool (dense, contiguous array + entity list), systems iterate the dense arrays.

#include <cstdint>
#include <limits>
#include <tuple>
#include <vector>

#include "scene_viewer/ecs/components.hpp"

namespace scene_viewer {

using EntityId = std::uint32_t;

/// Sparse set: components of one type stored contiguously in insertion order.
template <class T>
class ComponentPool {
  public:
    /// Adds or replaces the component of `e`.
    T& set(EntityId e, T value) {
        if (e >= sparse_.size()) sparse_.resize(e + 1, kAbsent);
        if (sparse_[e] != kAbsent) return dense_[sparse_[e]] = std::move(value);
        sparse_[e] = static_cast<std::uint32_t>(dense_.size());
        dense_.push_back(std::move(value));
        owners_.push_back(e);
        return dense_.back();
    }
    bool has(EntityId e) const { return e < sparse_.size() && sparse_[e] != kAbsent; }
    /// The component of `e`, or nullptr.
    T* get(EntityId e) { return has(e) ? &dense_[sparse_[e]] : nullptr; }
    const T* get(EntityId e) const { return has(e) ? &dense_[sparse_[e]] : nullptr; }
    /// Contiguous components; owners()[i] is the entity of dense()[i].
    std::vector<T>& dense() { return dense_; }
    const std::vector<T>& dense() const { return dense_; }
    const std::vector<EntityId>& owners() const { return owners_; }
    std::size_t size() const { return dense_.size(); }
    void clear() {
        sparse_.clear();
        dense_.clear();
        owners_.clear();
    }

  private:
    static constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> sparse_;
    std::vector<T> dense_;
    std::vector<EntityId> owners_;
};

/// Calls f(entity, first_component, other_components...) for every entity that has a component
/// in each pool, in the order of `first`'s dense array (the pool that drives the join). Pools
/// passed const give const components. f must not add to or remove from the pools.
template <class F, class First, class... Rest>
void for_each(F&& f, First& first, Rest&... rest) {
    const auto& owners = first.owners();
    auto& dense = first.dense();
    for (std::size_t i = 0; i < dense.size(); ++i) {
        const EntityId e = owners[i];
        const auto components = std::make_tuple(rest.get(e)...);
        const bool all = std::apply([](auto*... p) { return ((p != nullptr) && ...); }, components);
        if (!all) continue;
        std::apply([&](auto*... p) { f(e, dense[i], *p...); }, components);
    }
}

/// All entities and their components (the thesis's Engine holds one World).
struct World {
    ComponentPool<Transform> transforms;
    ComponentPool<WorldMatrix> world_matrices;
    ComponentPool<MeshRef> meshes;
    ComponentPool<Material> materials;
    ComponentPool<Camera> cameras;
    ComponentPool<SourceEntity> sources;

    /// A new entity id with no components.
    EntityId create();
    /// Number of entities created since the last clear().
    std::size_t entity_count() const { return next_; }
    /// Removes every entity and component.
    void clear();

  private:
    EntityId next_ = 0;
};

}  // namespace scene_viewer
