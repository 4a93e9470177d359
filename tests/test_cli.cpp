// The knitsim binary against its command-line contract (docs/commands.md), and the output writers.
//   bad input: exit 2, one stderr line naming the field, nothing written;
//   a settled run: exit 0 and outputs that agree with each other;
//   an unsettled run: exit 3 with the outputs still written.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/cli_runner.hpp"

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/vtk.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;
using namespace knitsim::test;
namespace fs = std::filesystem;

namespace {

// Whether summary.json's units text `units` ("a, b m; c N/m") lists `name` with a unit.
bool names_a_unit(const std::string& units, const std::string& name) {
  for (std::size_t at = units.find(name); at != std::string::npos; at = units.find(name, at + 1)) {
    const bool starts = at == 0 || units[at - 1] == ' ';
    const char after = at + name.size() < units.size() ? units[at + name.size()] : '\0';
    if (starts && (after == ',' || after == ' ')) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("bad input: exit 2, one stderr line naming the field, --out not created") {
  TempDir tmp("bad");
  const fs::path out = tmp.path / "should-not-exist";
  fs::create_directories(tmp.path / "a-file-parent");
  std::ofstream(tmp.path / "a-file") << "x";
  struct Case {
    std::string args, names;
  };
  const std::vector<Case> cases = {
      {"--set model.stifness=900", "did you mean model.stiffness?"},
      {"--set model.topology=d", "model.topology = d: must be one of a, b, c"},
      {"--set model.stiffness=nan", "model.stiffness = nan: must be a number > 0 N/m"},
      {"--set model.stiffness=-3", "model.stiffness = -3: must be > 0 N/m"},
      {"--set model.natural_length=0", "model.natural_length = 0: must be > 0 m"},
      {"--scene /nonexistent/scene.toml", "scene: cannot read /nonexistent/scene.toml"},
      {"--scene four_cornr", "built-in scenes: four_corner"},
      {"--rtol 2", "--rtol = 2: must be in (0, 1)"},
      {"--rtol abc", "--rtol"},
      {"--max-steps 0", "--max-steps = 0"},
      {"--integrator nope", "--integrator = nope: must be one of"},
      {"--gmres-preconditioner ilu", "--gmres-preconditioner: ilu not in {none,block-jacobi"},
      {"--eps-lin 0", "--eps-lin = 0: must be in (0, 1]"},
      {"--krylov-dim 501", "--krylov-dim = 501: must be in 0..500"},
      {"--max-restarts -1", "--max-restarts = -1: must be in 0..1000"},
      {"--factorization dense", "--factorization: dense not in {auto,simplicial,block,supernodal}"},
      {"--bogus", "--bogus"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.args);
    const Run r = run_knitsim("drape " + c.args + " --out '" + out.string() + "'", tmp);
    CHECK(r.status == 2);
    const auto err = lines(r.err);
    REQUIRE(err.size() == 1);
    CHECK(err[0].rfind("knitsim: error: ", 0) == 0);
    CHECK(err[0].find(c.names) != std::string::npos);
    CHECK(r.out.empty());
    CHECK(!fs::exists(out));
  }
  // --out that is a file, or below a file.
  for (const fs::path& bad : {tmp.path / "a-file", tmp.path / "a-file" / "sub"}) {
    CAPTURE(bad);
    const Run r =
        run_knitsim("drape --set model.natural_length=0.1 --out '" + bad.string() + "'", tmp);
    CHECK(r.status == 2);
    REQUIRE(lines(r.err).size() == 1);
    CHECK(r.err.find("--out " + bad.string()) != std::string::npos);
  }
  const Run none = run_knitsim("", tmp);
  CHECK(none.status == 2);
  CHECK(lines(none.err).size() == 1);
  const Run list = run_knitsim("list scenery", tmp);
  CHECK(list.status == 2);
  CHECK(lines(list.err).size() == 1);
}

TEST_CASE("a settled drape: exit 0, summary, nodes, VTK, PNG and manifest agree") {
  TempDir tmp("good");
  const fs::path out = tmp.path / "nested" / "run";
  // implicit-euler: a fixed-step method whose result does not hang on adaptive-solver tuning.
  const Run r =
      run_knitsim("drape --set model.natural_length=0.1 --integrator implicit-euler --out '" +
                      out.string() + "'",
                  tmp);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.out.find("equilibrium") != std::string::npos);
  CHECK(r.err.empty());  // no progress line: stderr is not a terminal

  const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
  CHECK(summary["status"] == "equilibrium");
  CHECK(summary["scene"] == "four_corner");
  CHECK(summary["params"]["natural_length"] == 0.1);
  // The units of params and options come from the key table's rows: every number has one, in
  // the unit `knitsim list keys` shows (pins.span's pin_span: 1).
  for (const char* block : {"params", "options"}) {
    const std::string units = summary["units"][block];
    for (const auto& item : summary[block].items())
      if (item.value().is_number() && item.key() != "seed")  // an integer key, no unit
        CHECK(names_a_unit(units, item.key()));
  }
  CHECK(summary["units"]["params"] ==
        "width, natural_length, perturbation m; areal_density g/m^2; stiffness N/m; damping N s/m; "
        "elongation_limit %; pin_span 1; pin_move_time s");
  CHECK(units_text(KeyModel::Drape, {"pin_span", "width", "damping", "stiffness"}) ==
        "width m; stiffness N/m; damping N s/m; pin_span 1");  // the table's order, by unit
  const int n = summary["grid"]["n"];
  REQUIRE(n == 5);  // floor(0.5 / 0.1 + 0.5)
  CHECK(summary["grid"]["particles"] == 36);
  CHECK(summary["grid"]["dof"] == 3 * 32);
  // Units for a reader without the source: every top-level number that is not a count has one.
  const auto& units = summary["units"];
  CHECK(units["centre_sag_m"] == "m");
  CHECK(units["max_strain"].get<std::string>().find("a fraction") != std::string::npos);
  for (const char* key : {"t_start, t_final", "dt", "residual, residual_floor", "edge_coefficients",
                          "params", "wall_seconds, cpu_seconds", "factor_flops"})
    CHECK(units.contains(key));
  CHECK(summary["certificate"] == "stable_minimum");
  CHECK(summary["newton_step"].get<double>() <=
        std::max(summary["options"]["position_tol"].get<double>(),
                 summary["newton_floor"].get<double>()));
  CHECK(summary["steps"].get<long>() > 0);
  // 96 unknowns in 3 x 3 particle blocks: the automatic factorisation is the block LDL^T.
  CHECK(summary["options"]["factorization"] == "auto");
  CHECK(summary["factorization"] == "block");
  // One factorisation's cost, and the summary line that prints it for the run's factorisations.
  const double flops = summary["factor_flops"].get<double>();
  CHECK(flops >= summary["factor_nonzeros"].get<double>() + 96);
  CHECK(r.out.find("linear algebra  " + std::to_string(summary["factorisations"].get<long>()) +
                   " symmetric factorisations (block LDL^T, " + format_number(flops, 3) +
                   " flops each") != std::string::npos);

  // nodes.csv: (n+1)^2 rows; the 4 corners pinned at z = 0; the centre sag is theirs.
  const auto rows = lines(slurp(out / "nodes.csv"));
  REQUIRE(rows.size() == 1u + (n + 1) * (n + 1));
  CHECK(rows[0] == "id,i,j,x,y,z,pinned");
  int pinned = 0;
  double centre_z = 0.0;
  for (size_t k = 1; k < rows.size(); ++k) {
    std::istringstream in(rows[k]);
    std::string cell;
    std::vector<double> v;
    while (std::getline(in, cell, ',')) v.push_back(std::stod(cell));
    REQUIRE(v.size() == 7u);
    const int i = static_cast<int>(v[1]), j = static_cast<int>(v[2]);
    CHECK(v[0] == i * (n + 1) + j);
    if (v[6] == 1.0) {
      ++pinned;
      CHECK(v[5] == 0.0);
      CHECK(((i == 0 || i == n) && (j == 0 || j == n)));
    }
    if ((i == 2 || i == 3) && (j == 2 || j == 3)) centre_z += v[5] / 4.0;
  }
  CHECK(pinned == 4);
  CHECK(summary["centre_sag_m"].get<double>() == Approx(-centre_z).epsilon(1e-12));

  const std::string vtk = slurp(out / "drape.vtk");
  CHECK(vtk.rfind("# vtk DataFile Version 3.0\n", 0) == 0);
  CHECK(vtk.find("POINTS 36 double") != std::string::npos);
  CHECK(vtk.find("POLYGONS 25 125") != std::string::npos);
  CHECK(vtk.find("SCALARS pinned int 1") != std::string::npos);
  CHECK(vtk.find("VECTORS displacement double") != std::string::npos);

  CHECK(slurp(out / "drape.png").rfind("\x89PNG\r\n\x1a\n", 0) == 0);
  const auto manifest = nlohmann::json::parse(slurp(out / "manifest.json"));
  CHECK(manifest["command_line"].get<std::string>().find("model.natural_length=0.1") !=
        std::string::npos);
  CHECK(!manifest["git_commit"].get<std::string>().empty());
  CHECK(manifest["libraries"]["sundials"].get<std::string>().rfind("6.", 0) == 0);
  CHECK(manifest["libraries"]["suitesparse"].get<std::string>().rfind("5.", 0) == 0);
  CHECK(manifest["libraries"].contains("mpi"));
  CHECK(manifest["command"] == "drape");
  CHECK(summary["integrator"] == "implicit-euler");
  CHECK(manifest["options"]["integrator"] == "implicit-euler");
  for (const auto& e : fs::directory_iterator(out)) CHECK(e.path().extension() != ".tmp");
}

TEST_CASE("drape --no-pictures writes every output but drape.png, the same numbers") {
  TempDir tmp("nopictures");
  const std::string args = "drape --quiet --out '";
  const fs::path with = tmp.path / "with", without = tmp.path / "without";
  REQUIRE(run_knitsim(args + with.string() + "'", tmp).status == 0);
  REQUIRE(run_knitsim(args + without.string() + "' --no-pictures", tmp).status == 0);
  CHECK(fs::exists(with / "drape.png"));
  CHECK(!fs::exists(without / "drape.png"));
  for (const char* f : {"nodes.csv", "edges.csv", "drape.vtk"}) {
    INFO(f);
    CHECK(slurp(without / f) == slurp(with / f));
  }
  CHECK(fs::exists(without / "summary.json"));
  CHECK(fs::exists(without / "manifest.json"));
}

TEST_CASE("an unsettled drape exits 3 and still writes its outputs") {
  TempDir tmp("unsettled");
  const fs::path out = tmp.path / "run";
  const Run r =
      run_knitsim("drape --integrator cvode-bdf --set model.natural_length=0.1 --set run.t_max=0.5 "
                  "--quiet --out '" +
                      out.string() + "'",
                  tmp);
  CHECK(r.status == 3);
  CHECK(r.out.empty());  // --quiet
  const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
  CHECK(summary["status"] == "time_limit");
  CHECK(summary["t_final"].get<double>() == Approx(0.5));
  CHECK(fs::exists(out / "nodes.csv"));
  CHECK(fs::exists(out / "drape.png"));

  // Stopped after one step the two_corner sheet is still flat: its side edges cannot be
  // measured (no 5 distinct abscissae). The run is still reported, with the reason.
  const fs::path flat = tmp.path / "flat";
  const Run one = run_knitsim(
      "drape --scene two_corner --max-steps 1 --quiet --out '" + flat.string() + "'", tmp);
  CHECK(one.status == 3);
  const auto flat_summary = nlohmann::json::parse(slurp(flat / "summary.json"));
  CHECK(flat_summary["status"] == "step_limit");
  CHECK(flat_summary.contains("edges_error"));
  CHECK_FALSE(flat_summary.contains("edge_coefficients"));
  CHECK(fs::exists(flat / "nodes.csv"));
}

TEST_CASE("knitsim list shows the registry and the built-in scenes") {
  TempDir tmp("list");
  const Run integ = run_knitsim("list integrators", tmp);
  CHECK(integ.status == 0);
  CHECK(lines(integ.out).size() == 1 + integrator_catalog().size());
  for (const IntegratorInfo& info : integrator_catalog())
    CHECK(integ.out.find(info.name) != std::string::npos);
  const Run scenes = run_knitsim("list scenes", tmp);
  CHECK(scenes.status == 0);
  CHECK(scenes.out.find("two_corner_slack") != std::string::npos);
  CHECK(scenes.out.find("hung from its four corners") != std::string::npos);
}

TEST_CASE("output writers: tables, VTK, atomic files and output folders") {
  RunStats st;  // an explicit run: no line
  CHECK(linear_algebra_summary(st).empty());
  st.factorisations = 125;  // KLU or block-Jacobi GMRES: factorisations, but no cost counted
  CHECK(linear_algebra_summary(st).empty());
  st.factorization = "block";
  st.factor_flops = 2.12e9;
  CHECK(linear_algebra_summary(st) ==
        "125 symmetric factorisations (block LDL^T, 2.12e+09 flops each, 265 GFlop in all)");
  st.factorization = "supernodal";
  CHECK(linear_algebra_summary(st).find("(supernodal LL^T, ") != std::string::npos);
  st.lin_iters = 2401;  // CG between the factorisations (cg-ldl)
  CHECK(linear_algebra_summary(st) ==
        "125 symmetric factorisations (supernodal LL^T, 2.12e+09 flops each, 265 GFlop in all); "
        "2401 Krylov iterations");
  st.factor_flops = 0.0;  // block-Jacobi GMRES: iterations only
  CHECK(linear_algebra_summary(st) == "2401 Krylov iterations");
  st.steps = 14, st.rhs_evals = 23, st.jac_evals = 22, st.lin_setups = 9;
  CHECK(steps_summary(st) == "14 (RHS 23, Jac 22, LS setups 9)");

  Table t;
  t.columns = {"a", "b"};
  t.rows = {{"1", "x,y"}, {"say \"hi\"", ""}};
  CHECK(t.csv() == "a,b\n1,\"x,y\"\n\"say \"\"hi\"\"\",\n");
  CHECK(t.markdown() == "| a | b |\n|---|---|\n| 1 | x,y |\n| say \"hi\" |  |\n");
  CHECK(t.text() == "a         b\n1         x,y\nsay \"hi\"  \n");

  VtkPolyData d;
  d.title = "t";
  d.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}};
  d.cells = {{0, 1, 2, 3}, {1, 4, 2}};
  d.point_ints = {{"pinned", {1, 0, 0, 0, 1}}};
  const std::string vtk = to_vtk(d);
  CHECK(vtk.find("POLYGONS 2 9\n4 0 1 2 3\n3 1 4 2\n") != std::string::npos);
  CHECK(vtk.find("POINT_DATA 5\nSCALARS pinned int 1\nLOOKUP_TABLE default\n1\n0\n0\n0\n1\n") !=
        std::string::npos);

  TempDir tmp("writers");
  write_file_atomic(tmp.path / "f.txt", "one");
  write_file_atomic(tmp.path / "f.txt", "two");
  CHECK(slurp(tmp.path / "f.txt") == "two");
  CHECK(!fs::exists(tmp.path / "f.txt.tmp"));
  CHECK_THROWS_AS(write_file_atomic(tmp.path / "no-such-dir" / "f.txt", "x"), OutputError);

  // Default folders are fresh: a second one in the same second gets -2.
  const fs::path cwd = fs::current_path();
  fs::current_path(tmp.path);
  const fs::path a = make_output_dir("", "stem");
  const fs::path b = make_output_dir("", "stem");
  fs::current_path(cwd);
  CHECK(a.parent_path() == "out");
  CHECK(a.filename().string().rfind("stem-", 0) == 0);
  CHECK(a != b);
  CHECK(fs::is_directory(tmp.path / a));
  CHECK(fs::is_directory(tmp.path / b));
  // Nothing is made in it: the lock (held by this process until it ends) is on the folder.
  CHECK(fs::is_empty(tmp.path / a));
}

TEST_CASE("drape --target: edges.csv always, Eq. 5 objective against a target") {
  TempDir tmp("target");
  const std::string common = "drape --set model.natural_length=0.1 --integrator implicit-euler ";
  const fs::path twin = tmp.path / "twin";
  REQUIRE(run_knitsim(common + "--out '" + twin.string() + "'", tmp).status == 0);
  CHECK(fs::exists(twin / "edges.csv"));
  const auto s = nlohmann::json::parse(slurp(twin / "summary.json"));
  REQUIRE(s["edge_coefficients"].size() == 4);
  // A coefficient target made of this run's own edges.
  const fs::path target = tmp.path / "twin.csv";
  {
    std::ofstream f(target);
    f.precision(17);
    f << "scene,edge,kind,a,b\n";
    for (const auto& [edge, c] : s["edge_coefficients"].items())
      for (int k = 0; k < 5; ++k)
        f << "four_corner," << edge << ",coeff," << k << "," << c[k].get<double>() << "\n";
  }
  const fs::path same = tmp.path / "same", stiffer = tmp.path / "stiffer";
  REQUIRE(
      run_knitsim(common + "--target '" + target.string() + "' --out '" + same.string() + "'", tmp)
          .status == 0);
  REQUIRE(run_knitsim(common + "--set model.stiffness=1100 --target '" + target.string() +
                          "' --out '" + stiffer.string() + "'",
                      tmp)
              .status == 0);
  const double e_same = nlohmann::json::parse(slurp(same / "summary.json"))["objective"];
  const double e_stiffer = nlohmann::json::parse(slurp(stiffer / "summary.json"))["objective"];
  CHECK(e_same < 1e-9);
  CHECK(e_stiffer > 0.1);  // percent; a stiffer sheet sags visibly less
  CHECK(fs::exists(same / "target_edges.csv"));
  // A target without the scene's edges: one line, exit 2, nothing written.
  const fs::path wrong = tmp.path / "wrong.csv", none = tmp.path / "none";
  {
    std::ofstream f(wrong);
    f << "scene,edge,kind,a,b\n";
    for (int k = 0; k < 5; ++k) f << "two_corner,top,coeff," << k << ",0\n";
  }
  const Run bad =
      run_knitsim(common + "--target '" + wrong.string() + "' --out '" + none.string() + "'", tmp);
  CHECK(bad.status == 2);
  CHECK(lines(bad.err).size() == 1);
  CHECK(bad.err.find("--target") != std::string::npos);
  CHECK_FALSE(fs::exists(none));
}

TEST_CASE("fit --optimizer lm: a noise-free target of the model itself, end to end") {
  TempDir tmp("fit-lm");
  // A 30 cm sheet (n = round(0.3 / L0) = 5..8 over Table 3's L0 box: few, small drapes) at
  // k = 852 N/m, L0 = 0.05 m (n = 6), topology a; its own edges as a coefficient target.
  const std::string sheet = "--scene four_corner --set fabric.width=0.3 ";
  const fs::path made = tmp.path / "made";
  REQUIRE(run_knitsim("drape " + sheet +
                          "--set model.stiffness=852 --set model.natural_length=0.05 "
                          "--set model.topology=a --rtol 1e-8 --out '" +
                          made.string() + "'",
                      tmp)
              .status == 0);
  const auto made_summary = nlohmann::json::parse(slurp(made / "summary.json"));
  const fs::path target = tmp.path / "target.csv";
  {
    std::ofstream f(target);
    f.precision(17);
    f << "scene,edge,kind,a,b\n";
    for (const auto& [edge, c] : made_summary["edge_coefficients"].items())
      for (int k = 0; k < 5; ++k)
        f << "four_corner," << edge << ",coeff," << k << "," << c[k].get<double>() << "\n";
  }
  const std::string fit = "fit " + sheet + "--target '" + target.string() + "' ";
  const fs::path out = tmp.path / "fit";
  const Run r = run_knitsim(fit + "--optimizer lm --quiet --out '" + out.string() + "'", tmp);
  INFO(r.err);
  REQUIRE(r.status == 0);
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  // The data are the model's own at a point of the box, so the minimum is 0; the synthetic
  // targets' noise floor is 1-3 %, so 1e-3 % means the fit found the truth's valley, not a
  // neighbouring n bracket or topology (which leave > 0.1 %).
  const double objective = s["objective"].get<double>();
  CHECK(std::isfinite(objective));
  CHECK(objective < 1e-3);
  CHECK(s["params"]["topology"] == "a");
  // Only k / L0 is determined (k and L0 slide together): it is recovered.
  const double ratio =
      s["params"]["stiffness"].get<double>() / s["params"]["natural_length"].get<double>();
  CHECK(std::abs(ratio / (852.0 / 0.05) - 1.0) < 1e-3);
  // Budget: one screening drape per topology (3) x n bracket (<= 4: n = 5..8), then the 2
  // refined starts with <= 15 evaluations each (src/fit/lm_fit.hpp defaults).
  const long evaluations = s["evaluations"].get<long>();
  CHECK(evaluations >= 3 * 3);
  CHECK(evaluations <= 3 * 4 + 2 * 15);
  CHECK(fs::exists(out / "starts.csv"));
  CHECK(fs::exists(out / "drape" / "summary.json"));

  // Bad options: one line, exit 2, nothing written.
  const fs::path none = tmp.path / "none";
  for (const auto& [args, names] : std::vector<std::pair<std::string, std::string>>{
           {"--optimizer xyz", "--optimizer = xyz"},
           {"--optimizer lm --resume", "--resume: only with --optimizer ica"}}) {
    CAPTURE(args);
    const Run bad = run_knitsim(fit + args + " --out '" + none.string() + "'", tmp);
    CHECK(bad.status == 2);
    REQUIRE(lines(bad.err).size() == 1);
    CHECK(bad.err.find(names) != std::string::npos);
    CHECK_FALSE(fs::exists(none));
  }
}

TEST_CASE("knitsim list keys: every scene key with its unit, default and accepted values") {
  TempDir tmp("list-keys");
  const Run text = run_knitsim("list keys", tmp);
  REQUIRE(text.status == 0);
  CHECK(lines(text.out).size() == 1 + scene_key_table().rows.size());
  for (const std::string& key : scene_keys()) CHECK(text.out.find(key) != std::string::npos);
  // The knit's keys and the run options' flags too, each saying which model reads it.
  for (const std::string& key : scene_keys(KeyModel::Knit))
    CHECK(text.out.find(key) != std::string::npos);
  CHECK(text.out.find("--eps-lin") != std::string::npos);
  // The ranges are the validators' own, the defaults sample 1's.
  CHECK(text.out.find("> 0 N/m") != std::string::npos);
  CHECK(text.out.find("a = structural + shear + bending, b = structural + shear, c = structural "
                      "+ bending") != std::string::npos);
  const Run md = run_knitsim("list keys --format markdown", tmp);
  REQUIRE(md.status == 0);
  CHECK(md.out.rfind("| key | model | unit | default | accepted | meaning |", 0) == 0);
  CHECK(md.out.find("| model.stiffness | drape | N/m | 852 | > 0 N/m |") != std::string::npos);
  CHECK(md.out.find("| run.t_max | both | s | 1e+07 | in [1e-9, 1e15] s |") != std::string::npos);
  CHECK(md.out.find("| --rtol | both | 1 | 1e-06 | in (0, 1) |") != std::string::npos);
  // drape --help lists the keys and defines the topologies.
  const Run help = run_knitsim("drape --help", tmp);
  CHECK(help.out.find("model.elongation_limit") != std::string::npos);
  CHECK(help.out.find("c = structural + bending") != std::string::npos);
}

TEST_CASE("a partial scene file: one note naming the physical keys left at sample 1's values") {
  TempDir tmp("partial-scene");
  const fs::path partial = tmp.path / "partial.toml";
  std::ofstream(partial) << "# my sheet\n[fabric]\nareal_density = 180.0\n\n[model]\n"
                            "stiffness = 1500.0\nnatural_length = 0.04\n";
  const std::string out = " --no-pictures --quiet --out '" + (tmp.path / "o").string() + "'";
  const Run r = run_knitsim("drape --scene '" + partial.string() + "'" + out, tmp);
  REQUIRE(r.status == 0);
  REQUIRE(lines(r.err).size() == 1);
  CHECK(r.err.find("knitsim drape: note: " + partial.string() +
                   " leaves fabric.width = 0.5 m, model.damping = 12 N s/m, "
                   "model.elongation_limit = 5 %, model.topology = a, pins.layout = four_corner "
                   "at sample 1's values") != std::string::npos);
  // A key given by --set is not inherited; the keys the file gives are not listed.
  const Run set = run_knitsim("drape --scene '" + partial.string() +
                                  "' --set model.elongation_limit=0" + out,
                              tmp);
  CHECK(set.err.find("model.elongation_limit") == std::string::npos);
  CHECK(set.err.find("model.stiffness") == std::string::npos);
  // A file that names every physical key (docs/examples/my_fabric.toml), and a built-in scene:
  // no note.
  CHECK(run_knitsim("drape --scene '" KNITSIM_DOCS_DIR "/examples/my_fabric.toml'" + out, tmp)
            .err.empty());
  CHECK(run_knitsim("drape --scene four_corner" + out, tmp).err.empty());
}

TEST_CASE("the lab-data example fits; upside-down lab data are warned about") {
  TempDir tmp("lab-fit");
  const std::string lab = KNITSIM_DOCS_DIR "/examples/lab_targets.csv";
  const std::string fit = "fit --scene '" KNITSIM_DOCS_DIR "/examples/my_fabric.toml' --target ";
  const fs::path out = tmp.path / "fit";
  const Run r = run_knitsim(fit + "'" + lab + "' --optimizer lm --out '" + out.string() + "'", tmp);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.empty());
  CHECK(fs::exists(out / "drape" / "drape.png"));
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  // Made from a drape of my_fabric.toml at k = 600 N/m, L0 = 0.04 m, topology a, with 0.1 mm
  // noise (docs/examples/make_lab_targets.py): the fit finds its k / L0 within a few percent
  // (the noise floor), its topology and its mesh.
  const double ratio =
      s["params"]["stiffness"].get<double>() / s["params"]["natural_length"].get<double>();
  CHECK(std::abs(ratio / (600.0 / 0.04) - 1.0) < 0.05);
  CHECK(s["params"]["topology"] == "a");
  CHECK(s["objective"].get<double>() < 2.5);
  // What each number is measured in, as drape's and knit's summaries say it.
  CHECK(s["units"]["objective"].get<std::string>().rfind("%", 0) == 0);
  CHECK(s["units"].contains("identifiability"));
  // The printout leads with what the edges determine and says why the rest is not.
  const size_t ratio_row = r.out.find("k / L0 (determined)");
  CHECK(ratio_row != std::string::npos);
  CHECK(ratio_row < r.out.find("\nstiffness "));
  CHECK(r.out.find("not determined by the edges: stiffness and natural_length enter the edges "
                   "only as k / L0 at a fixed mesh; damping does not enter the equilibrium; "
                   "the elongation limit") != std::string::npos);
  CHECK(r.out.find("note: the fitted natural_length") != std::string::npos);
  CHECK(r.out.find("also sets the mesh: n = round(fabric.width / L0) = 10 cells per side") !=
        std::string::npos);

  // The same photos with z growing downward (image rows): one warning line, the fit runs on.
  const fs::path flipped = tmp.path / "flipped.csv";
  {
    std::ifstream in(lab);
    std::ofstream f(flipped);
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("four_corner,", 0) == 0) {
        const size_t comma = line.rfind(',');
        const double z = std::stod(line.substr(comma + 1));
        line = line.substr(0, comma + 1) + format_number(-z, 17);
      }
      f << line << "\n";
    }
  }
  const Run up = run_knitsim(fit + "'" + flipped.string() + "' --optimizer lm --quiet --out '" +
                                 (tmp.path / "up").string() + "'",
                             tmp);
  REQUIRE(lines(up.err).size() == 1);
  CHECK(up.err.find("knitsim fit: warning: --target " + flipped.string() +
                    ": every edge of four_corner hangs above its pins") != std::string::npos);
  // Without --quiet the warning comes again after the result table, where the reader looks;
  // --no-pictures leaves the fitted drape without its picture.
  const fs::path loud = tmp.path / "loud";
  const Run again = run_knitsim(fit + "'" + flipped.string() + "' --optimizer lm --no-pictures " +
                                    "--out '" + loud.string() + "'",
                                tmp);
  const std::vector<std::string> warned = lines(again.err);
  REQUIRE(warned.size() == 2);
  CHECK(warned[0] == warned[1]);
  CHECK(fs::exists(loud / "drape" / "summary.json"));
  CHECK(!fs::exists(loud / "drape" / "drape.png"));
}
