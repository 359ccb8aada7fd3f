// Mortar contact between two named surfaces of a model, in one call.
#pragma once

#include <string>

#include "contact/mortar_contact.hpp"
#include "core/model.hpp"

namespace emdae {

/// Frictionless mortar contact of the edge set `slave` ("body.set") on the
/// edge set `master`: a MortarContact added to the model's system. `name`
/// defaults to "slave/master". Throws ModelError (key "slave", "master" or
/// "name"; "" for what the pair as a whole cannot be) and then adds nothing.
const ContactPair& add_mortar_contact(Model& model, const std::string& slave,
                                      const std::string& master, std::string name = "",
                                      const ContactOptions& options = {});

}  // namespace emdae
