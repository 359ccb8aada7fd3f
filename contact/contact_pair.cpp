#include "contact/contact_pair.hpp"

#include <memory>
#include <utility>
#include <vector>

namespace emdae {

const ContactPair& add_mortar_contact(Model& model, const std::string& slave,
                                      const std::string& master, std::string name,
                                      const ContactOptions& options) {
  const auto surface = [&model](const std::string& set, const char* key) {
    model.find_set(set, Model::SetKind::Edges, key);
    return ContactSurface{set, model.edges(set)};
  };
  ContactSurface s = surface(slave, "slave"), m = surface(master, "master");
  if (slave == master) throw ModelError("master", "slave and master are the same surface");
  if (name.empty()) name = slave + "/" + master;
  for (const auto& other : model.contacts())
    if (other.name == name) throw ModelError("name", "duplicate contact name");
  ContactPair pair{
      name, slave, master, static_cast<int>(s.edges.size()), static_cast<int>(m.edges.size()),
      0,    0};
  std::unique_ptr<MortarContact> contact;
  try {
    contact =
        std::make_unique<MortarContact>(model.system(), std::move(s), std::move(m), name, options);
  } catch (const std::invalid_argument& e) {
    throw ModelError("", e.what());
  }
  if (options.modified_mass) {
    // Both checked before either changes (a body one element through has
    // no nodes to take its surface's mass).
    for (const auto& [set, which] : {std::pair{slave, "slave"}, std::pair{master, "master"}}) try {
        model.modify_mass(set, false);
      } catch (const ModelError& e) {
        throw ModelError("modified_mass", std::string(which) + " surface " + set + ": " + e.what());
      }
    model.modify_mass(slave);
    model.modify_mass(master);
    pair.modified_mass = true;
  }
  // Surfaces that meet (a block's bottom and its sides, each a slave of
  // its own) are one chain for the surface depth, whichever pair declared
  // them: every pair's chains take in every other pair's surfaces joined
  // to them, until nothing more joins.
  std::vector<MortarContact*> mortars{contact.get()};
  for (const auto& set : model.system().unilateral())
    if (auto* other = dynamic_cast<MortarContact*>(set.get())) mortars.push_back(other);
  for (bool joined = true; joined;) {
    joined = false;
    for (MortarContact* a : mortars)
      for (const MortarContact* b : mortars)
        if (a != b)
          for (const ContactSurface* chain : {&b->slave_surface(), &b->master_surface()})
            joined = a->add_joined_surface(chain->edges) || joined;
  }
  return model.add_contact(std::move(pair), std::move(contact));
}

}  // namespace emdae
