// Scenes: built-in and file loading, --set overrides, one-line errors naming the key, and the
// drape run's measured quantities against the positions it returns.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "src/scene/material_run.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;
namespace fs = std::filesystem;

namespace {

// The message of the std::invalid_argument that f throws ("" if none).
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::string load_error(const std::string& scene, const std::vector<std::string>& sets = {}) {
  return error_of([&] { load_scene(scene, sets); });
}

// A scene file in a fresh temporary folder.
struct TempScene {
  fs::path path;
  TempScene(const std::string& name, const std::string& text) {
    const fs::path dir =
        fs::temp_directory_path() / ("knitsim-test-scene-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    path = dir / name;
    std::ofstream(path) << text;
  }
  ~TempScene() { fs::remove_all(path.parent_path()); }
};

}  // namespace

TEST_CASE("built-in scenes load with the paper's sample-1 parameters") {
  REQUIRE(builtin_scenes().size() == 5);
  for (const auto& [name, text] : builtin_scenes()) {
    const Scene s = load_scene(name);
    if (s.material.kind == DrapeModelKind::Material) continue;  // below
    CAPTURE(name);
    CHECK(s.name == name);
    CHECK(s.source == "built-in");
    CHECK(s.params.stiffness == 852.0);
    CHECK(s.params.damping == 12.0);
    CHECK(s.params.elongation_limit == 5.0);
    CHECK(s.params.natural_length == 0.049);
    CHECK(s.params.topology == 'a');
    CHECK(s.params.areal_density == 41.65);
    CHECK(s.params.width == 0.5);
    CHECK(s.options.t_max == 1e7);
    CHECK(s.options.equilibrium_tol == 1e-8);
    CHECK(!scene_description(text).empty());
  }
  CHECK(load_scene("four_corner").params.layout == PinLayout::FourCorner);
  const Scene two = load_scene("two_corner");
  CHECK(two.params.layout == PinLayout::TwoCorner);
  CHECK(two.params.pin_span == 1.0);
  const Scene slack = load_scene("two_corner_slack");
  CHECK(slack.params.layout == PinLayout::TwoCorner);
  CHECK(slack.params.pin_span == 0.6);
  CHECK(slack.params.pin_move_time == 100.0);
  CHECK(slack.params.perturbation == 1e-6);
  // The material model's scenes (docs/material_drape.md).
  const Scene cantilever = load_scene("cantilever");
  CHECK(cantilever.material.kind == DrapeModelKind::Material);
  CHECK(cantilever.material.clamps == ClampLayout::Edge);
  CHECK(cantilever.material.overhang == 0.04);
  CHECK(cantilever.material.bending_wale == 1.5696e-5);
  const Scene corners = load_scene("four_corner_material");
  CHECK(corners.material.kind == DrapeModelKind::Material);
  CHECK(corners.material.clamps == ClampLayout::Corners);
  CHECK(corners.material.clamp_size == 0.05);
  CHECK(scene_description(builtin_scenes()[0].second) ==
        "Sample 1 (Tables 2 and 4) hung from its four corners (paper 1, Fig. 12).");
}

TEST_CASE("--set overrides change the parameters, in order, parsed by the key's type") {
  const Scene s = load_scene(
      "four_corner", {"model.stiffness=900", "model.topology=b", "fabric.areal_density = 58.26",
                      "model.seed=7", "pins.layout=\"two_corner\"", "pins.span=0.5",
                      "run.t_max=5e3", "run.equilibrium_tol=1e-6", "scene.name=mine"});
  CHECK(s.params.stiffness == 900.0);  // a key given twice by --set is refused (below)
  CHECK(s.params.topology == 'b');
  CHECK(s.params.areal_density == 58.26);
  CHECK(s.params.seed == 7u);
  CHECK(s.params.layout == PinLayout::TwoCorner);
  CHECK(s.params.pin_span == 0.5);
  CHECK(s.options.t_max == 5e3);
  CHECK(s.options.equilibrium_tol == 1e-6);
  CHECK(s.name == "mine");
  // Untouched keys keep the scene's values.
  CHECK(s.params.damping == 12.0);
  CHECK(s.params.natural_length == 0.049);
  CHECK(scene_keys().size() == 43);  // 30 + the material fit's box (12) and fit.parameters
}

TEST_CASE("unknown keys name the key and suggest the nearest valid one") {
  CHECK(load_error("four_corner", {"model.stifness=900"}) ==
        "model.stifness: unknown key; did you mean model.stiffness?");
  CHECK(load_error("four_corner", {"fabric.areal_densty=40"}) ==
        "fabric.areal_densty: unknown key; did you mean fabric.areal_density?");
  CHECK(load_error("four_corner", {"run.tmax=1"}) ==
        "run.tmax: unknown key; did you mean run.t_max?");
  // Nothing near: the valid keys are listed instead of a misleading guess.
  const std::string far = load_error("four_corner", {"colour=red"});
  CHECK(far.rfind("colour: unknown key; valid keys: scene.name fabric.width", 0) == 0);
  CHECK(far.find('\n') == std::string::npos);

  TempScene file("typo.toml", "[model]\nstiffness = 900\nnatural_lenght = 0.05\n");
  CHECK(load_error(file.path.string()) ==
        "model.natural_lenght: unknown key; did you mean model.natural_length? (" +
            file.path.string() + " line 3)");
  TempScene section("section.toml", "[modle]\nstiffness = 900\n");
  CHECK(load_error(section.path.string())
            .rfind("modle.stiffness: unknown key; did you mean model.stiffness?", 0) == 0);
}

TEST_CASE("bad values give one line naming the field and the accepted range") {
  struct Case {
    std::string set, expected;
  };
  const std::vector<Case> cases = {
      {"model.topology=d", "model.topology = d: must be one of a, b, c"},
      {"model.topology=ab", "model.topology = ab: must be one of a, b, c"},
      {"model.stiffness=-5", "model.stiffness = -5: must be > 0 N/m"},
      {"model.stiffness=nan", "model.stiffness = nan: must be a number > 0 N/m"},
      {"model.stiffness=inf", "model.stiffness = inf: must be a number > 0 N/m"},
      {"model.stiffness=abc", "model.stiffness = abc: must be a number > 0 N/m"},
      {"model.stiffness=", "model.stiffness = : must be a number > 0 N/m"},
      {"model.stiffness=9e9x", "model.stiffness = 9e9x: must be a number > 0 N/m"},
      {"model.natural_length=0", "model.natural_length = 0: must be > 0 m"},
      {"model.damping=-1", "model.damping = -1: must be >= 0 N s/m"},
      {"pins.span=1.5", "pins.span = 1.5: must be in (0, 1]"},
      {"pins.span=x", "pins.span = x: must be a number in (0, 1]"},
      {"pins.layout=three_corner",
       "pins.layout = three_corner: must be one of four_corner, two_corner"},
      {"model.seed=-1", "model.seed = -1: must be an integer in 0..4294967295"},
      {"model.seed=1.5", "model.seed = 1.5: must be an integer in 0..4294967295"},
      {"run.t_max=0", "run.t_max = 0: must be in [1e-9, 1e15] s"},
      {"run.t_max=1e22", "run.t_max = 1e22: must be in [1e-9, 1e15] s"},  // as typed
      {"model.natural_length=0.34",
       "model.natural_length = 0.34: must be <= fabric.width / 1.5 = 0.333333 m (2 cells per "
       "side at least)"},
      {"run.equilibrium_tol=abc", "run.equilibrium_tol = abc: must be a number > 0"},
      {"scene.name=a b", "scene.name = a b: must be a non-empty name of letters, digits, _ and -"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.set);
    CHECK(load_error("four_corner", {c.set}) == c.expected);
  }
  CHECK(load_error("four_corner", {"model.stiffness"}) ==
        "--set model.stiffness: expected key=value, e.g. model.stiffness=900");
}

TEST_CASE("scene files: partial files, types, missing files and TOML syntax errors") {
  TempScene partial("my_fabric.toml",
                    "# x\n# A test fabric.\n[model]\nstiffness = 700   # an integer is a number\n"
                    "[pins]\nlayout = \"two_corner\"\n");
  const Scene s = load_scene(partial.path.string(), {"model.damping=15"});
  CHECK(s.name == "my_fabric");  // the file's stem when [scene] name is absent
  CHECK(s.source == partial.path.string());
  CHECK(s.params.stiffness == 700.0);
  CHECK(s.params.damping == 15.0);
  CHECK(s.params.layout == PinLayout::TwoCorner);
  CHECK(s.params.natural_length == DrapeParams{}.natural_length);

  TempScene typed("typed.toml", "[model]\nstiffness = \"abc\"\n");
  CHECK(load_error(typed.path.string()) ==
        "model.stiffness = 'abc': must be a number > 0 N/m (" + typed.path.string() + " line 2)");
  TempScene nan("nan.toml", "[model]\ndamping = nan\n");
  CHECK(
      load_error(nan.path.string()).rfind("model.damping = nan: must be a number >= 0 N s/m", 0) ==
      0);
  // An integer with no exact double (beyond 2^53) is read as the nearest double, then
  // range-checked like any number (it used to escape as "bad optional access").
  TempScene big("big.toml", "[model]\nstiffness = 9007199254740993\n");
  CHECK(load_scene(big.path.string()).params.stiffness == 9007199254740992.0);
  TempScene big_t("big_t.toml", "[run]\nt_max = 9007199254740993\n");
  CHECK(load_error(big_t.path.string()) ==
        "run.t_max = 9007199254740993: must be in [1e-9, 1e15] s");  // as written
  TempScene topo("topo.toml", "[model]\ntopology = 1\n");
  CHECK(load_error(topo.path.string()).rfind("model.topology = 1: must be one of a, b, c", 0) == 0);

  TempScene syntax("syntax.toml", "[model]\nstiffness = 900\ndamping = = 3\n");
  const std::string err = load_error(syntax.path.string());
  CHECK(err.rfind("scene " + syntax.path.string() + ": TOML syntax error at line 3, column ", 0) ==
        0);
  CHECK(err.find('\n') == std::string::npos);

  const std::string missing = load_error("/nonexistent/scene.toml");
  CHECK(missing == "scene: cannot read /nonexistent/scene.toml: No such file or directory");
  CHECK(load_error("four_cornr") ==
        "scene: cannot read four_cornr: No such file or directory (built-in scenes: four_corner "
        "two_corner two_corner_slack cantilever four_corner_material)");
  CHECK(load_error(fs::temp_directory_path().string()) ==
        "scene: cannot read " + fs::temp_directory_path().string() + ": is a directory");
}

// knitsim knit --set, through the same table: the knit's keys and the run's, not the drape's.
std::string knit_error(const std::vector<std::string>& sets) {
  return error_of([&] { knit_scene("c.chart", sets).validate(); });
}

TEST_CASE("knit keys are rows of the table: set, validated and refused like the drape's") {
  const Scene s = knit_scene("dir/tucks.chart", {"knit.contact=0", "knit.network=paper",
                                                 "run.t_max=50", "knit.damping=1e-3"});
  CHECK(s.name == "tucks");
  CHECK(s.chart == "dir/tucks.chart");
  CHECK(s.knit.contact_ratio == 0.0);
  CHECK(s.knit.network == KnitNetwork::Paper);
  CHECK(s.knit.damping == 1e-3);
  CHECK(s.options.t_max == 50.0);
  CHECK(scene_keys(KeyModel::Knit).front() == "knit.loop_radius");
  // Each model refuses the other's keys as unknown, with its own keys as the suggestions.
  CHECK(knit_error({"model.stiffness=900"})
            .rfind("model.stiffness: unknown key; valid keys: knit.", 0) == 0);
  CHECK(load_error("four_corner", {"knit.contact=0"}).rfind("knit.contact: unknown key", 0) == 0);
  CHECK(load_error("four_corner", {"knit.contact=0"}).find("knit.loop_radius") ==
        std::string::npos);
  CHECK(knit_error({"knit.stabiliser=2"}) == "knit.stabiliser = 2: must be in [0, 1]");
  CHECK(knit_error({"knit.network=bare"}) ==
        "knit.network = bare: must be stabilised (the default) or paper (paper 2's network)");
  CHECK(knit_error({"knit.damping=abc"}) == "knit.damping = abc: must be a number >= 0 N s/m");
  CHECK(knit_error({"knit.contact=1", "knit.bending=1"})
            .rfind("knit.bending = 1: must be 0 with knit.contact > 0", 0) == 0);
  CHECK(knit_error({"knit.network=paper", "knit.contact=1"}) ==
        "--set knit.stabiliser, knit.bending or knit.contact with knit.network = paper: paper 2's "
        "network has no stabiliser, bending or contact (drop one of them)");
  CHECK(knit_error({"knit.network=paper"}).empty());  // the paper network ignores the defaults
  CHECK(knit_error({"run.position_tol=1"}) == "run.position_tol = 1: must be in (0, 1e-2] m");
}

TEST_CASE("messages say what was typed: values as given, long text cut, one value per key") {
  // The value as typed, not as a double prints (100.0000001 printed at 6 digits is 100, which
  // looks in range).
  CHECK(knit_error({"knit.contact=100.0000001"}) ==
        "knit.contact = 100.0000001: must be in [0, 100]");
  CHECK(load_error("four_corner", {"model.stiffness=-0.0000123456789"}) ==
        "model.stiffness = -0.0000123456789: must be > 0 N/m");
  // A value changed after it was typed is shown as it is now.
  Scene s = load_scene("four_corner", {"model.stiffness=900"});
  s.params.stiffness = -1.0;
  CHECK(error_of([&] { s.validate(); }) == "model.stiffness = -1: must be > 0 N/m");
  // Long keys and values: the first 60 characters, "...", the length.
  const std::string long_key(500000, 'k');
  const std::string unknown = load_error("four_corner", {long_key + "=1"});
  CHECK(unknown.rfind(std::string(60, 'k') + "... (500000 characters): unknown key; valid keys: ",
                      0) == 0);
  CHECK(unknown.size() < 1000);
  const std::string long_value = "-" + std::string(200, '1');
  CHECK(load_error("four_corner", {"model.stiffness=" + long_value}) ==
        "model.stiffness = " + long_value.substr(0, 60) + "... (201 characters): must be > 0 N/m");
  CHECK(load_error("four_corner", {"pins.layout=" + std::string(100, 'x')}) ==
        "pins.layout = " + std::string(60, 'x') +
            "... (100 characters): must be one of four_corner, two_corner");
  // The same key twice among the --set is refused (the first value would vanish unchecked);
  // a --set over the scene file's value is what --set is for.
  CHECK(load_error("four_corner", {"model.stiffness=-1", "model.stiffness=900"}) ==
        "--set model.stiffness: given twice (-1, then 900); give each key once");
  CHECK(knit_error({"knit.contact=0", "knit.damping=1", "knit.contact=5"}) ==
        "--set knit.contact: given twice (0, then 5); give each key once");
  CHECK(load_scene("four_corner", {"model.stiffness=900"}).params.stiffness == 900.0);
  // An empty key says so, with the form expected.
  CHECK(load_error("four_corner", {"=5"}) ==
        "--set =5: the key is empty; expected key=value, e.g. model.stiffness=900");
  CHECK(knit_error({" =5"}) ==
        "--set  =5: the key is empty; expected key=value, e.g. knit.contact=0");
}

TEST_CASE("the target scene follows the pins, not the scene's name") {
  CHECK(target_scene_name(load_scene("four_corner")) == "four_corner");
  CHECK(target_scene_name(load_scene("four_corner", {"pins.layout=two_corner"})) == "two_corner");
  CHECK(target_scene_name(load_scene("two_corner", {"pins.layout=four_corner"})) == "four_corner");
  CHECK(target_scene_name(load_scene("two_corner", {"pins.span=0.8"})) == "two_corner_slack");
  CHECK(target_scene_name(load_scene("two_corner_slack", {"pins.span=1"})) == "two_corner");
  CHECK(target_scene_name(load_scene("four_corner", {"scene.name=two_corner"})) == "four_corner");
}

TEST_CASE("run options are validated under the names the user writes") {
  Scene s = load_scene("four_corner");
  s.options.rtol = 2.0;
  CHECK(error_of([&] { s.validate(); }) == "--rtol = 2: must be in (0, 1)");
  s.options.rtol = 1e-6;
  s.options.max_wall_seconds = -1.0;
  CHECK(error_of([&] { s.validate(); }).rfind("--max-wall = -1: ", 0) == 0);
}

TEST_CASE("run_drape: a small four_corner drape is mirror-symmetric and its sag is the centre's") {
  // n = 5 cells: the centre is the mean of particles (2,2), (2,3), (3,2), (3,3).
  const Scene s = load_scene("four_corner", {"model.natural_length=0.1"});
  const DrapeResult r = run_drape(s, "implicit-euler");
  REQUIRE(r.stats.status == RunStatus::Equilibrium);
  REQUIRE(r.grid.n == 5);
  REQUIRE(r.positions.size() == 36u);
  CHECK(r.stats.certificate == "stable_minimum");

  double centre = 0.0;
  for (int i : {2, 3})
    for (int j : {2, 3}) centre += r.positions[r.grid.index(i, j)].z / 4.0;
  CHECK(r.centre_sag == Approx(-centre).epsilon(1e-12));
  CHECK(r.centre_sag > 0.0);

  // Pins stay where they started; the square's symmetries (i <-> j, i <-> n - i) hold at rest.
  for (int p : r.grid.network.spec().pinned) {
    CHECK(r.positions[p].z == 0.0);
    CHECK(r.positions[p].x == r.rest[p].x);
  }
  const int n = r.grid.n;
  double asymmetry = 0.0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double z = r.positions[r.grid.index(i, j)].z;
      asymmetry = std::max(asymmetry, std::abs(z - r.positions[r.grid.index(j, i)].z));
      asymmetry = std::max(asymmetry, std::abs(z - r.positions[r.grid.index(n - i, j)].z));
    }
  CHECK(asymmetry < 1e-6 * r.centre_sag);

  // The reported max strain is that of the returned positions (structural springs included).
  double strain = 0.0;
  for (const Spring& sp : r.grid.network.spec().springs)
    strain = std::max(strain, norm(r.positions[sp.b] - r.positions[sp.a]) / sp.rest - 1.0);
  CHECK(r.max_strain == Approx(strain).epsilon(1e-9));

  CHECK(error_of([&] { run_drape(s, "no-such-method"); }).rfind("integrator = no-such-method", 0) ==
        0);
}

TEST_CASE("model.kind = material: its keys reach the sheet, and no mirror is assumed") {
  const Scene s = load_scene("four_corner_material",
                             {"mesh.cells=30", "material.bending_wale=2e-5",
                              "material.membrane_course=700", "material.poisson=0.4",
                              "fabric.length=0.4", "clamps.size=0.04"});
  const MaterialSheetParams p = s.material.sheet(s.params);
  CHECK(p.cells == 30);
  CHECK(p.cells_y() == 24);
  CHECK(p.bending_wale == 2e-5);
  CHECK(p.membrane_course == 700.0);
  CHECK(p.poisson_cw == 0.4);
  CHECK(p.areal_density == 41.65);
  REQUIRE(p.patches.size() == 4);
  CHECK(p.patches[3].x0 == Approx(0.46));
  CHECK(p.patches[3].y1 == 0.4);
  // The cantilever's jaw line falls on a row: the overhang is exactly clamps.overhang.
  const Scene c = load_scene("cantilever", {"clamps.overhang=0.0371", "mesh.cells=5"});
  const MaterialSheetParams q = c.material.sheet(c.params);
  const MaterialSheet sheet(q);
  const double hy = sheet.hy();
  int jaw = 0;
  while (sheet.free_index(sheet.vertex(jaw + 1, 0)) < 0) ++jaw;
  CHECK(q.length - jaw * hy == Approx(0.0371).epsilon(1e-12));
  CHECK(jaw >= 1);
  // An anisotropic sheet has no diagonal mirror: eighth is refused with one line naming it;
  // half and quarter are taken (their sheet-level check is run_material_drape's).
  for (const char* aniso : {"material.bending_wale=2e-5", "material.membrane_wale=1500"})
    CHECK_THROWS_WITH(load_scene("four_corner_material", {"model.symmetry=eighth", aniso}),
                      Catch::Matchers::Contains("model.symmetry = eighth: the sheet has no "
                                                "diagonal mirror"));
  for (const char* mirror : {"half", "quarter", "eighth"})
    CHECK_NOTHROW(load_scene("four_corner_material", {std::string("model.symmetry=") + mirror}));
  CHECK_THROWS_WITH(load_scene("cantilever", {"mesh.cells=1"}),
                    "mesh.cells = 1: must be in [2, 2000]");
  // Paper 1's scenes do not see the material keys.
  CHECK(load_scene("four_corner").material.kind == DrapeModelKind::Paper);
}

TEST_CASE("material drapes: auto takes the mirrors the sheet has, never one it lacks",
          "[material][mirrors]") {
  // Isotropic: an eighth, certified on the whole sheet; the same sag as the whole sheet.
  const Scene iso = load_scene("four_corner_material", {"mesh.cells=12"});
  const MaterialDrapeResult e = run_material_drape(iso, "equilibrium");
  CHECK(std::string(symmetry_name(e.mirrors)) == "eighth");
  CHECK(e.whole_sheet_checked);
  CHECK(e.stats.certificate == "stable_minimum");
  const MaterialDrapeResult w =
      run_material_drape(load_scene("four_corner_material", {"mesh.cells=12", "model.symmetry=none"}),
                         "equilibrium");
  CHECK(std::string(symmetry_name(w.mirrors)) == "none");
  CHECK(w.integrated_dof == w.sheet->dof());
  CHECK(e.integrated_dof < w.integrated_dof / 6);
  CHECK(std::abs(e.centre_sag - w.centre_sag) < 1e-12);
  // Anisotropic (B_w = 2 B_c, or A_w != A_c): a quarter, never the diagonal.
  for (const char* aniso : {"material.bending_wale=2e-5", "material.membrane_wale=1200"}) {
    const MaterialDrapeResult q =
        run_material_drape(load_scene("four_corner_material", {"mesh.cells=12", aniso}),
                           "equilibrium");
    CHECK(std::string(symmetry_name(q.mirrors)) == "quarter");
    CHECK_FALSE(q.mirrors.diagonal);
  }
  // The cantilever's jaw: the x mirror; a quarter asked for is refused with one line.
  const MaterialDrapeResult c = run_material_drape(load_scene("cantilever"), "equilibrium");
  CHECK(std::string(symmetry_name(c.mirrors)) == "half");
  CHECK(c.mirrors.x);
  CHECK_THROWS_WITH(
      run_material_drape(load_scene("cantilever", {"model.symmetry=quarter"}), "equilibrium"),
      "model.symmetry = quarter: the y mirror: the clamps are not symmetric (use a smaller group, "
      "auto or none)");
}
