// [[bodies]], [[contacts]], [[dirichlet]] and [[loads]]: calls on the Model
// (core/model.hpp) and add_mortar_contact (contact/contact_pair.hpp), which
// compute the masses, lumped tractions and prescribed motions they imply.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "contact/contact_pair.hpp"
#include "core/gmsh_reader.hpp"
#include "core/modified_mass.hpp"
#include "integrators/stepper.hpp"
#include "scene/scene_reader.hpp"

namespace emdae::scene_reader {

// Memory a run needs per Q1 element (2D): the model and system, the sparse
// Jacobian and its KLU factors, the recorder's and the writers' vectors;
// measured as the peak resident size of `emdae run` (scheme em) on a ring of
// 10^5 elements: 1.08 GB, 10.8 KB per element (docs/reliability.md).
constexpr double kBytesPerElement = 11 * 1024;
// The same with linear_solver = "amg" (no factors: the hierarchy and
// GMRES's vectors instead), measured on a square of 708 x 708 elements
// (1 005 362 dofs): 2 762 MiB, 5.6 KiB per element (docs/performance.md §13).
constexpr double kBytesPerElementAmg = 6 * 1024;

std::string Builder::unique_name(const Fields& f, std::vector<std::string>& taken,
                                 const std::string& fallback, const char* what) const {
  std::string name = fallback;
  if (const auto given = f.optional_string("name")) {
    if (given->empty()) f.fail_key("name", "must not be empty, received \"\"");
    name = *given;
  }
  if (std::find(taken.begin(), taken.end(), name) != taken.end())
    f.fail_key("name", fmt::format("duplicate {} name, received \"{}\"", what, name));
  taken.push_back(name);
  return name;
}

Mesh Builder::mesh(const Fields& f) {
  const Fields m =
      f.table("mesh", "{type = \"ring\" | \"disk\" | \"rectangle\" | \"gmsh\", ...}", "a mesh");
  Mesh mesh = generated_mesh(m);
  // Any mesh may be turned about its area centroid (a square on its corner).
  if (const auto degrees = m.optional_number("rotation")) {
    if (!(std::abs(*degrees) <= 360.0))
      m.fail_key("rotation", "must be an angle in degrees in [-360, 360], received " +
                                 show(*m.find("rotation")));
    rotate_mesh(mesh, *degrees * M_PI / 180.0);
    mesh.description += fmt::format(", turned by {} degrees", *degrees);
  }
  return mesh;
}

void Builder::charge_elements(const Fields& m, std::string_view k, double elements) {
  Scene::Estimate& e = scene_.estimate;
  // [scheme] is read before the bodies. AMG serves em, midpoint, galpha and
  // statics (IDA's matrices have constraint rows: they go to an LU).
  const bool amg = settings().schemes.newton.linear_solver == KluSolver::Backend::Amg &&
                   settings().scheme != "ida";
  e.memory_bytes += elements * (amg ? kBytesPerElementAmg : kBytesPerElement);
  if (!(e.memory_bytes <= e.max_memory_bytes))
    m.fail_key(k,
               fmt::format("{:.0f} elements make the scene need about {:.0f} MB (the model, its "
                           "Jacobian and {}), more than limits.max_memory_mb = {:.0f} "
                           "(raise it with --set limits.max_memory_mb=N), received {}",
                           elements, e.memory_bytes / (1 << 20), amg ? "AMG hierarchy" : "factors",
                           e.max_memory_bytes / (1 << 20), show(*m.find(k))));
}

Mesh Builder::generated_mesh(const Fields& m) {
  const std::string type = m.string("type", "\"ring\", \"disk\", \"rectangle\" or \"gmsh\"");
  // Element counts beyond this are a typo, not a mesh (and would overflow).
  constexpr long kMaxCount = 100000, kMaxElements = 10000000;
  if (type == "ring") {
    m.only({"type", "centre", "inner_radius", "outer_radius", "around", "through", "rotation"});
    const Vec c = m.vector("centre", 2, "the ring's centre, 2 numbers");
    const double r_in = m.positive("inner_radius", "the inner radius, a positive number");
    const double r_out = m.positive("outer_radius", "the outer radius, a positive number");
    if (!(r_out > r_in))
      m.fail_key("outer_radius", "must exceed inner_radius = " + show_number(r_in) + ", received " +
                                     show(*m.find("outer_radius")));
    if (!m.has("around")) m.require("around", "elements around, an integer >= 3");
    if (!m.has("through")) m.require("through", "elements through the wall, an integer >= 1");
    const long around = m.integer_in("around", 0, 3, kMaxCount);
    const long through = m.integer_in("through", 0, 1, kMaxCount);
    if (around * through > kMaxElements)
      m.fail_key("through", fmt::format("{} x {} elements is more than {} in one body, received {}",
                                        around, through, kMaxElements, through));
    charge_elements(m, "through", static_cast<double>(around * through));
    return ring_mesh(Eigen::Vector2d(c[0], c[1]), r_in, r_out, static_cast<int>(around),
                     static_cast<int>(through));
  }
  if (type == "disk") {
    // A solid disk or a half/quarter of it (core/mesh.hpp, disk_mesh).
    m.only({"type", "centre", "radius", "per_quarter", "radial", "sector", "rotation"});
    const Vec c = m.vector("centre", 2, "the disk's centre, 2 numbers");
    const double r = m.positive("radius", "the radius, a positive number");
    if (!m.has("per_quarter"))
      m.require("per_quarter", "elements along a quarter of the circle, an even integer >= 2");
    if (!m.has("radial"))
      m.require("radial", "elements from the central square to the circle, an integer >= 1");
    const long per_quarter = m.integer_in("per_quarter", 0, 2, kMaxCount);
    if (per_quarter % 2 != 0)
      m.fail_key("per_quarter",
                 "must be even (the central square has per_quarter / 2 elements "
                 "a side in each quadrant), received " +
                     show(*m.find("per_quarter")));
    const long radial = m.integer_in("radial", 0, 1, kMaxCount);
    // Sector [from, to] in degrees, multiples of 90, 90 .. 360 wide.
    int first = 0, quadrants = 4;
    if (const auto sector = m.optional_vector("sector", 2)) {
      const double from = (*sector)[0], to = (*sector)[1];
      const auto quarter = [](double a) {
        return std::abs(a / 90.0 - std::round(a / 90.0)) < 1e-12;
      };
      if (!(std::abs(from) <= 360.0 && std::abs(to) <= 720.0 && quarter(from) && quarter(to) &&
            to > from && to - from <= 360.0))
        m.fail_key("sector",
                   "must be [from, to] in degrees, multiples of 90 with from in [-360, 360] and "
                   "to - from = 90, 180, 270 or 360 (e.g. [-90, 90]: the right half), received " +
                       show(*m.find("sector")));
      first = static_cast<int>(std::lround(from / 90.0));
      quadrants = static_cast<int>(std::lround((to - from) / 90.0));
    }
    const long per_quadrant = per_quarter * per_quarter / 4 + per_quarter * radial;
    if (per_quadrant * quadrants > kMaxElements)
      m.fail_key("radial", fmt::format("{} elements is more than {} in one body, received {}",
                                       per_quadrant * quadrants, kMaxElements, radial));
    charge_elements(m, "radial", static_cast<double>(per_quadrant * quadrants));
    return disk_mesh(Eigen::Vector2d(c[0], c[1]), r, static_cast<int>(per_quarter),
                     static_cast<int>(radial), first, quadrants);
  }
  if (type == "rectangle") {
    m.only(
        {"type", "origin", "width", "height", "nx", "ny", "grading", "grading_centre", "rotation"});
    const Vec o = m.vector("origin", 2, "the lower left corner, 2 numbers");
    const double w = m.positive("width", "the width, a positive number");
    const double h = m.positive("height", "the height, a positive number");
    if (!m.has("nx")) m.require("nx", "elements along x, an integer >= 1");
    if (!m.has("ny")) m.require("ny", "elements along y, an integer >= 1");
    const long nx = m.integer_in("nx", 0, 1, kMaxCount);
    const long ny = m.integer_in("ny", 0, 1, kMaxCount);
    if (nx * ny > kMaxElements)
      m.fail_key("ny", fmt::format("{} x {} elements is more than {} in one body, received {}", nx,
                                   ny, kMaxElements, ny));
    charge_elements(m, "ny", static_cast<double>(nx * ny));
    const Eigen::Vector2d lo(o[0], o[1]), hi(o[0] + w, o[1] + h);
    Mesh mesh = rectangle_mesh(lo, w, h, static_cast<int>(nx), static_cast<int>(ny));
    // Grading: element sizes growing away from a point (Hertz's contact).
    const auto grading = m.optional_vector("grading", 2);
    const auto centre = m.optional_vector("grading_centre", 2);
    if (centre && !grading)
      m.fail_key("grading_centre", "has no effect without grading = [px, py], received " +
                                       show(*m.find("grading_centre")));
    if (grading) {
      for (int d = 0; d < 2; ++d)
        if (!((*grading)[d] >= 1.0 && (*grading)[d] <= 10.0))
          m.fail_key("grading", "must be two powers in [1, 10] (1: uniform), received " +
                                    show(*m.find("grading")));
      const Eigen::Vector2d c =
          centre ? Eigen::Vector2d((*centre)[0], (*centre)[1]) : 0.5 * (lo + hi);
      if (!(c.x() >= lo.x() && c.x() <= hi.x() && c.y() >= lo.y() && c.y() <= hi.y()))
        m.fail_key("grading_centre",
                   fmt::format("must lie in the rectangle ({}, {}) .. ({}, {}), received {}",
                               lo.x(), lo.y(), hi.x(), hi.y(), show(*m.find("grading_centre"))));
      grade_mesh(mesh, lo, hi, c, Eigen::Vector2d((*grading)[0], (*grading)[1]));
    }
    return mesh;
  }
  if (type == "gmsh") {
    // A Gmsh MSH 4.1 file, relative to the scene file's folder; its physical
    // curves become the body's edge sets (see core/gmsh_reader.hpp).
    m.only({"type", "file", "surface", "rotation"});
    const std::string file = m.string("file", "the mesh file, a path relative to the scene");
    const std::string surface = m.optional_string("surface").value_or("");
    const std::filesystem::path base = std::filesystem::path(scene_.settings.source).parent_path();
    const std::string path = (base / file).string();
    Mesh mesh;
    try {
      mesh = read_gmsh(path, surface);
      mesh.description =
          fmt::format("gmsh {}{}, {} elements", file, surface.empty() ? "" : " (" + surface + ")",
                      mesh.n_elements());
    } catch (const std::exception& e) {
      m.fail_key("file", std::string(e.what()) + ", received \"" + file + "\"");
    }
    charge_elements(m, "file", static_cast<double>(mesh.n_elements()));
    return mesh;
  }
  m.fail_key("type", "unknown mesh type, received " + show(*m.find("type")) +
                         hint(type, {"ring", "disk", "rectangle", "gmsh"}, "mesh types"));
}

Material Builder::material(const Fields& f) const {
  const Fields m = f.table("material", "{model, young, poisson, density}", "a material");
  m.only({"model", "young", "poisson", "density"});
  MaterialModel model = MaterialModel::SaintVenantKirchhoff;
  if (const auto name = m.optional_string("model")) {
    try {
      model = parse_material_model(*name);
    } catch (const std::invalid_argument&) {
      m.fail_key("model", "unknown material model, received " + show(*m.find("model")) +
                              hint(*name, {"svk", "neo-hooke", "linear"}, "models"));
    }
  }
  const double young = m.positive("young", "Young's modulus E, a positive number");
  const double nu = m.number("poisson", "Poisson's ratio, in (-1, 0.5)");
  // nu -> 0.5 is incompressible (lambda infinite), nu <= -1 makes mu <= 0.
  if (!(nu > -1.0 && nu < 0.5))
    m.fail_key("poisson", "must be in (-1, 0.5), received " + show(*m.find("poisson")));
  const double rho = m.positive("density", "the mass density, a positive number");
  try {
    return make_material(model, young, nu, rho);
  } catch (const std::invalid_argument& e) {
    fail(m.where(), m.path(), e.what());
  }
}

void Builder::parse_body(const Fields& f) {
  f.only({"name", "mesh", "material", "velocity", "angular_velocity", "lumped_mass"});
  if (model().dim() != 2)
    fail(f.where(), f.path(),
         fmt::format("FE bodies are plane strain and need scene.dimension = 2, received "
                     "dimension {}",
                     model().dim()));
  const std::string name = f.string("name", "a unique name for the body");
  if (const auto it = body_where_.find(name); it != body_where_.end())
    f.fail_key("name", "duplicate body name, received \"" + name + "\" (first defined at " +
                           it->second + ")");
  Mesh m = mesh(f);
  const Material mat = material(f);
  BodyOptions options;
  options.lumped_mass = f.boolean("lumped_mass", false);
  const Vec v = f.optional_vector("velocity", 2).value_or(Vec::Zero(2));
  options.velocity = Eigen::Vector2d(v[0], v[1]);
  options.angular_velocity = f.optional_number("angular_velocity").value_or(0.0);
  model_call(f, [&] { model().add_body(name, std::move(m), mat, options); });
  body_where_[name] = f.where();
}

std::string Builder::set_ref(const Fields& f, std::string_view k, const toml::node& n,
                             Model::SetKind kind) const {
  const char* kind_name = kind == Model::SetKind::Nodes ? "node set" : "edge set";
  if (!n.is_string())
    f.fail_at(n, k,
              std::string(kind == Model::SetKind::Nodes ? "must name a " : "must name an ") +
                  kind_name + " as \"body.set\", received " + show_typed(n));
  const std::string& text = n.as_string()->get();
  try {
    model().find_set(text, kind, std::string(k));
  } catch (const ModelError& e) {
    // What there is to choose from: the bodies, or the sets of the body named.
    std::vector<std::string> bodies, sets;
    for (const auto& b : model().bodies()) bodies.push_back(b.name);
    const auto dot = text.find('.');
    std::string more;
    if (dot == std::string::npos) {
      more = " (e.g. \"" + (bodies.empty() ? std::string("ring") : bodies.front()) + ".outer\")";
    } else if (std::find(bodies.begin(), bodies.end(), text.substr(0, dot)) == bodies.end()) {
      more = bodies.empty() ? std::string(" (the scene has no [[bodies]] before this)")
                            : hint(text.substr(0, dot), bodies, "bodies");
    } else {
      const Mesh& m = model().body(text.substr(0, dot)).mesh;
      if (kind == Model::SetKind::Nodes)
        for (const auto& entry : m.node_sets) sets.push_back(entry.first);
      else
        for (const auto& entry : m.edge_sets) sets.push_back(entry.first);
      more = hint(text.substr(dot + 1), sets,
                  std::string(kind_name) + "s of '" + text.substr(0, dot) + "'");
    }
    f.fail_at(n, k, std::string(e.what()) + ", received " + show(n) + more);
  }
  return text;
}

TimeFunction Builder::time_function(const Fields& f, std::string_view k) const {
  if (!f.has(k)) return TimeFunction::constant(1.0);
  const Fields t =
      f.table(k, "{type = \"constant\" | \"ramp\" | \"hat\" | \"table\", ...}", "a time function");
  const std::string type = t.string("type", "\"constant\", \"ramp\", \"hat\" or \"table\"");
  const std::vector<std::string> types = {"constant", "ramp", "hat", "table"};
  if (std::find(types.begin(), types.end(), type) == types.end())
    t.fail_key("type", "unknown time function, received " + show(*t.find("type")) +
                           hint(type, types, "time functions"));
  if (type == "constant") {
    t.only({"type", "value"});
    return TimeFunction::constant(t.optional_number("value").value_or(1.0));
  }
  if (type == "ramp" || type == "hat") {
    const char* height = type == "ramp" ? "value" : "peak";
    t.only({"type", "start", "end", height});
    const double start = t.number("start", "the time it starts");
    const double end = t.number("end", "the time it ends, after start");
    if (!(end > start))
      t.fail_key("end", "must exceed start = " + show_number(start) + ", received " +
                            show(*t.find("end")));
    const double value = t.optional_number(height).value_or(1.0);
    return type == "ramp" ? TimeFunction::ramp(start, end, value)
                          : TimeFunction::hat(start, end, value);
  }
  t.only({"type", "times", "values"});
  const std::vector<double> times = t.numbers("times", "increasing times, a list of numbers");
  const std::vector<double> values =
      t.numbers("values", "the values at those times, a list of numbers");
  for (std::size_t i = 1; i < times.size(); ++i)
    if (!(times[i] > times[i - 1]))
      t.fail_key("times", "must increase strictly, received " + show(*t.find("times")));
  if (values.size() != times.size())
    t.fail_key("values", fmt::format("must have as many entries as times ({}), received {}",
                                     times.size(), show(*t.find("values"))));
  return TimeFunction::table(times, values);
}

void Builder::parse_contact(const Fields& f) {
  f.only({"name", "slave", "master", "search_margin", "modified_mass", "penalty"});
  const std::string slave =
      set_ref(f, "slave", Model::SetKind::Edges, "the slave surface, \"body.set\"");
  const std::string master =
      set_ref(f, "master", Model::SetKind::Edges, "the master surface, \"body.set\"");
  const std::string slave_body = slave.substr(0, slave.find('.'));
  if (slave != master && slave_body == master.substr(0, master.find('.')))
    warn(f.where(), "slave and master are on the same body '" + slave_body +
                        "': self-contact is not what the mortar contact was verified for");
  const std::string name = unique_name(f, contact_names_, slave + "/" + master, "contact");
  ContactSurfaces surfaces{name, slave, master, f.where(*f.find("slave")), f.where(), {}, {}};
  refuse_redundant_pair(f, surfaces);
  ContactOptions options;
  options.search_margin = f.optional_non_negative("search_margin").value_or(options.search_margin);
  options.modified_mass = f.boolean("modified_mass", false);
  options.penalty = f.optional_positive("penalty").value_or(0.0);
  if (options.penalty > 0.0 && options.modified_mass)
    f.fail_key("penalty",
               "a penalty contact keeps the nodes' mass: give either penalty or "
               "modified_mass = true, not both");
  model_call(f, [&] { add_mortar_contact(model(), slave, master, name, options); });
  contact_where_[name] = f.where();
  surfaces.modified_mass = options.modified_mass;
  if (const auto* n = f.find("modified_mass")) surfaces.mass_where = f.where(*n);
  contact_surfaces_.push_back(std::move(surfaces));
}

namespace {

// A surface's segments, each as its (smaller, larger) global node, sorted.
std::vector<std::pair<int, int>> surface_edges(const Model& model, const std::string& set) {
  std::vector<std::pair<int, int>> edges;
  for (const auto& e : model.edges(set))
    edges.emplace_back(std::min(e[0], e[1]), std::max(e[0], e[1]));
  std::sort(edges.begin(), edges.end());
  return edges;
}

bool meet(const std::vector<std::pair<int, int>>& a, const std::vector<std::pair<int, int>>& b) {
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (*i == *j) return true;
    *i < *j ? ++i : ++j;
  }
  return false;
}

}  // namespace

void Builder::refuse_redundant_pair(const Fields& f, ContactSurfaces& pair) const {
  pair.slave_edges = surface_edges(model(), pair.slave);
  pair.master_edges = surface_edges(model(), pair.master);
  // A slave segment in two pairs whose masters share a segment gives its
  // nodes the same weighted gap twice (equal constraint rows: the Newton
  // matrix is singular at the first contact); so does a pair and its swap
  // (each surface constrained against the other: two-pass mortar, which
  // over-constrains the interface). Surfaces that share only a corner node
  // (a block's bottom and side on one master), and a slave surface on
  // several masters without a common segment (a ring between two blocks),
  // are different pairs.
  for (std::size_t i = 0; i < contact_surfaces_.size(); ++i) {
    const ContactSurfaces& other = contact_surfaces_[i];
    const bool same =
        meet(pair.slave_edges, other.slave_edges) && meet(pair.master_edges, other.master_edges);
    const bool swapped =
        meet(pair.slave_edges, other.master_edges) && meet(pair.master_edges, other.slave_edges);
    if (!same && !swapped) continue;
    f.fail_key(
        "slave",
        fmt::format(
            "contact '{}' ({} on {}) repeats contacts[{}] '{}' ({} on {}, at {}): {}; "
            "the repeated constraints make the contact system singular, keep one "
            "pair, received \"{}\"",
            pair.name, pair.slave, pair.master, i, other.name, other.slave, other.master,
            other.slave_where,
            same ? "their slave surfaces share segments on master surfaces that share segments"
                 : "each pair's slave surface is the other's master (two-pass contact "
                   "is not supported)",
            pair.slave));
  }
}

void Builder::refuse_overlap() {
  // An equilibrium first pushes an overlap apart: the bearing's pre-stress.
  if (settings().statics.enabled) return;
  System& system = model().system();
  if (system.unilateral().empty()) return;
  const State state = initial_state(system);
  // Round-off, not overlap: relative to the size of the model (a weighted
  // gap is a length times a length).
  const int dim = system.dim();
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(dim, std::numeric_limits<double>::infinity());
  Eigen::VectorXd hi = -lo;
  for (int n = 0; n < system.n_nodes(); ++n) {
    lo = lo.cwiseMin(state.q.segment(dim * n, dim));
    hi = hi.cwiseMax(state.q.segment(dim * n, dim));
  }
  const double size = (hi - lo).norm();
  const double tolerance = 1e-9 * size * size;
  for (const auto& set : system.unilateral()) {
    set->prepare(state.q, state.v, settings().static_only ? 0.0 : settings().time.dt);
    for (int i = 0; i < set->size(); ++i) {
      // The weighted gap without the coverage barrier: at a crossing of the
      // surfaces the nodes next to it are partly covered, and the barrier
      // (up to 0.3 of a node's weight) would lift their gaps above zero.
      const double phi = set->overlap_gap(i, state.q);
      if (!(phi < -tolerance)) continue;  // apart, touching, or nothing opposite (+inf)
      const auto at = contact_where_.find(set->name());
      fail(at == contact_where_.end() ? loc_.start() : at->second,
           fmt::format("contacts[{}]", std::distance(contact_names_.begin(),
                                                     std::find(contact_names_.begin(),
                                                               contact_names_.end(), set->name()))),
           fmt::format("the bodies overlap at the start: {} is inside the master surface "
                       "(weighted gap {:.6g}); move them apart, or add [statics] to push the "
                       "overlap apart first, received contact '{}'",
                       set->describe(i), phi, set->name()));
    }
  }
}

void Builder::refuse_unsupported_massless() {
  // A static analysis takes no dynamic step (and solves with the exact
  // gradient, which needs no hand-over).
  if (settings().static_only) return;
  const System& system = model().system();
  if (!system.has_massless_nodes()) return;
  const int dim = system.dim();
  const auto& massless = system.is_massless();
  const auto& prescribed = system.is_prescribed();
  auto is_massless = [&](int a) { return massless[static_cast<std::size_t>(system.dof(a, 0))]; };
  auto is_free = [&](int a) { return !prescribed[static_cast<std::size_t>(system.dof(a, 0))]; };
  // What StepProblem hands each massless node's forces to, and (for naming
  // the contacts involved) every node of the elements it is in.
  const std::vector<std::vector<int>> around = massive_free_neighbours(system);
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(system.n_nodes()));
  for (const auto& term : system.potentials()) {
    std::vector<int> nodes;
    for (int d : term->dofs())
      if (d % dim == 0) nodes.push_back(d / dim);
    for (int a : nodes)
      if (is_massless(a)) {
        auto& near = neighbours[static_cast<std::size_t>(a)];
        near.insert(near.end(), nodes.begin(), nodes.end());
      }
  }
  for (const auto& group : system.mass_groups())
    for (int a : group.massless) {
      if (!is_free(a) || around[static_cast<std::size_t>(a)].size() >= 2) continue;
      // The contacts whose modified mass made the node or its element
      // neighbours massless.
      const auto& near = neighbours[static_cast<std::size_t>(a)];
      std::vector<std::size_t> involved;
      for (std::size_t i = 0; i < contact_surfaces_.size(); ++i) {
        const ContactSurfaces& c = contact_surfaces_[i];
        if (!c.modified_mass) continue;
        bool touches = false;
        for (const auto* edges : {&c.slave_edges, &c.master_edges})
          for (const auto& e : *edges)
            touches = touches || std::find(near.begin(), near.end(), e.first) != near.end() ||
                      std::find(near.begin(), near.end(), e.second) != near.end();
        if (touches) involved.push_back(i);
      }
      std::string body_node = "node " + std::to_string(a);
      for (const auto& b : model().bodies())
        if (a >= b.node(0) && a < b.node(b.mesh.n_nodes()))
          body_node =
              fmt::format("node {} of body '{}' (its mesh node {})", a, b.name, a - b.node(0));
      std::string names;
      for (std::size_t i : involved)
        names += fmt::format("{}contacts[{}] '{}' (modified_mass at {})", names.empty() ? "" : ", ",
                             i, contact_surfaces_[i].name, contact_surfaces_[i].mass_where);
      const std::size_t last = involved.empty() ? 0 : involved.back();
      fail(involved.empty() ? loc_.start() : contact_surfaces_[last].mass_where,
           fmt::format("contacts[{}].modified_mass", last),
           fmt::format("{} is massless and its elements have {} free node{} with mass, fewer "
                       "than the two its forces go to (surfaces with a modified mass meet at "
                       "it, or its neighbours are held); modified masses of {}: set "
                       "modified_mass = false on one of them, received true",
                       body_node, around[static_cast<std::size_t>(a)].size(),
                       around[static_cast<std::size_t>(a)].size() == 1 ? "" : "s",
                       names.empty() ? std::string("the contacts") : names));
    }
}

void Builder::parse_dirichlet(const Fields& f) {
  f.only({"nodes", "fixed", "displacement", "time_function", "components"});
  const std::string set = set_ref(f, "nodes", Model::SetKind::Nodes, "the node set, \"body.set\"");
  const bool fixed = f.boolean("fixed", false);
  const auto u = f.optional_vector("displacement", 2);
  if (fixed && u)
    f.fail_key("displacement", "give either fixed = true or a displacement, not both, received " +
                                   show(*f.find("displacement")));
  if (!fixed && !u)
    f.fail_key("fixed", "nothing prescribed: give fixed = true or displacement = [ux, uy]" +
                            std::string(f.has("fixed") ? ", received false" : ""));
  if (!u && f.has("time_function"))
    f.fail_key("time_function", "only a displacement has a time function, received " +
                                    show(*f.find("time_function")));
  Components components = Components::XY;
  if (const auto c = f.optional_string("components")) {
    if (*c == "x") {
      components = Components::X;
    } else if (*c == "y") {
      components = Components::Y;
    } else if (*c != "xy") {
      f.fail_key("components",
                 "must be \"xy\", \"x\" or \"y\", received " + show(*f.find("components")));
    }
  }
  if (!u) return model_call(f, [&] { model().fix(set, components); });
  const TimeFunction g = time_function(f, "time_function");
  if (g(0.0) != 0.0)
    warn(f.where(), "the displacement's time function is " + show_number(g(0.0)) +
                        " at t = 0: the nodes of " + set + " start displaced");
  model_call(f, [&] { model().prescribe_displacement(set, *u, g, components); });
}

void Builder::parse_load(const Fields& f) {
  f.only({"name", "type", "on", "body", "torque", "acceleration", "traction", "time_function"});
  const std::string type = f.string("type", "\"torque\", \"body_force\" or \"traction\"");
  const std::vector<std::string> types = {"torque", "body_force", "traction"};
  if (std::find(types.begin(), types.end(), type) == types.end())
    f.fail_key("type", "unknown load type, received " + show(*f.find("type")) +
                           hint(type, types, "load types"));
  // Keys of the other load types are mistakes, not options.
  const std::map<std::string, std::vector<std::string>> keys = {
      {"torque", {"on", "torque"}},
      {"body_force", {"body", "acceleration"}},
      {"traction", {"on", "traction"}}};
  for (const auto& k : {"on", "body", "torque", "acceleration", "traction"}) {
    const auto& mine = keys.at(type);
    if (f.has(k) && std::find(mine.begin(), mine.end(), k) == mine.end())
      f.fail_key(k, "not a key of a " + type + " load (its keys: " + join(mine) + "), received " +
                        show(*f.find(k)));
  }
  const std::string name =
      unique_name(f, load_names_, fmt::format("{} {}", type, load_names_.size()), "load");
  const TimeFunction g = time_function(f, "time_function");
  if (type == "torque") {
    const std::string on =
        set_ref(f, "on", Model::SetKind::Nodes, "the node set it acts on, \"body.set\"");
    const double torque = f.number("torque", "the torque (moment), a number");
    model_call(f, [&] { model().add_torque(name, on, torque, g); });
  } else if (type == "body_force") {
    const auto& n = f.require("body", "the name of the body it acts on");
    if (!n.is_string()) f.fail_at(n, "body", "must name a body, received " + show_typed(n));
    const Vec b = f.vector("acceleration", 2, "the force per unit mass, 2 numbers");
    model_call(f, [&] { model().add_body_force(name, n.as_string()->get(), b, g); });
  } else {
    const std::string on =
        set_ref(f, "on", Model::SetKind::Edges, "the edge set it acts on, \"body.set\"");
    const Vec t = f.vector("traction", 2, "the force per unit (reference) length, 2 numbers");
    model_call(f, [&] { model().add_traction(name, on, t, g); });
  }
}

}  // namespace emdae::scene_reader
