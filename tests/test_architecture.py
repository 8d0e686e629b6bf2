"""The package's architecture, read from its imports (issue 15): layers that import only downwards,
no import cycles, PETSc in one layer, size limits, and ``import ancf_petsc`` without PETSc.

The layers, lowest first (README.md, "Architecture"); a module may import its own layer and the
layers below it, never above:
"""
import ast
import os
import subprocess
import sys

import pytest

from helpers import ROOT

PACKAGE = os.path.join(ROOT, "ancf_petsc")
#: layer of each top-level component of ancf_petsc (sub-package or root module)
LAYERS = [
    ("errors", "version", "status", "yamlio", "registry", "native"),  # vocabulary shared by everything; YAML
    # input; registries that find their modules; compiled kernels (native.load)
    ("physics",),                             # element 3363, sections and cubature, materials, kernels
    ("linalg",),                              # PETSc options, linear solvers, log events (one home)
    ("contact", "outline_formats"),           # contact points, projection, multipliers, laws; outline files
    ("config",),                              # YAML → validated ModelSpec (key-path errors)
    ("geometry_input", "model"),              # measured outlines; ModelSpec → Model
    ("io", "parallel"),                       # results on disk; layouts and partitions
    ("petsc",),                               # Problem: PETSc Vec/Mat, SNES callbacks, exchange
    ("solving",),                             # SNES options, load stepping, one run
    ("viz",),                                 # figures from outputs
    ("workflows",),                           # studies, stability maps, accuracy ladders, sweeps
    ("api", "paper", "__init__"),             # the public API; the paper's reproduction
]
LAYER = {c: k for k, names in enumerate(LAYERS) for c in names}
#: components that may import petsc4py / mpi4py (api only to initialise PETSc on first use)
PETSC_COMPONENTS = {"linalg", "petsc", "solving", "api"}
#: functions longer than 60 lines, each with the reason it stays in one piece
LONG_FUNCTIONS = {
    "workflows/sweep/slurm.py:write_slurm": "one bash script, written line by line in order",
    "workflows/sweep/spec.py:load_sweep": "one pass over a sweep file's keys, each checked in place",
    "config/sections.py:_source": "one pass over a geometry source's keys, each checked in place",
    "physics/sections_file.py:load_sections_file": "one pass over a sections file's keys",
    "physics/section.py:make_outline": "the steps of eq. (11) and their checks, in order",
    "physics/cubature.py:compress_rule": "one algorithm (moment-preserving rule compression)",
    "physics/cubature.py:gauss_green_rule": "one algorithm (Gauss-Green cubature, eq. 11)",
    "geometry_input/merge.py:_assemble": "one algorithm (outlines merged along shared boundaries)",
    "model/build.py:build_model": "the model's parts built in dependency order",
    "contact/multipliers.py:build_space": "one construction (the Bernstein pressure space)",
    "config/bundle.py:expand_bundle": "one expansion of a bundle into beams, supports and loads",
    "viz/render.py:_render": "one figure's layout, in drawing order",
    "viz/charts.py:stability_chart": "one figure's layout, in drawing order",
    "workflows/accuracy.py:select_and_run": "one ladder: solve, estimate, stop",
}


def _modules(package: str = PACKAGE) -> dict[str, str]:
    """Dotted module name → file, for every module of the package."""
    out = {}
    for base, _, files in os.walk(package):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(base, f)
                rel = os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".")
                out[rel[:-9] if rel.endswith(".__init__") else rel] = path
    return out


MODULES = _modules()


def _imports(name: str, path: str) -> list[tuple[str, int]]:
    """(imported module, line) of every import in a module (also inside functions), resolved."""
    tree = ast.parse(open(path).read())
    package = name if path.endswith("__init__.py") else name.rsplit(".", 1)[0]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1])
                mod = f"{base}.{node.module}" if node.module else base
            else:
                mod = node.module
            for a in node.names:           # "from package import module" imports the module
                sub = f"{mod}.{a.name}"
                out.append((sub if sub in MODULES else mod, node.lineno))
    return out


def _component(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


GRAPH = {m: [(i, ln) for i, ln in _imports(m, p) if i in MODULES] for m, p in MODULES.items()}


def test_every_component_has_a_layer():
    assert {_component(m) for m in MODULES} <= set(LAYER), set(_component(m) for m in MODULES) - set(LAYER)


def test_imports_only_go_down_the_layers():
    upward = [f"{m} (layer {LAYER[_component(m)]}) imports {i} (layer {LAYER[_component(i)]}) at line {ln}"
              for m, edges in GRAPH.items() for i, ln in edges
              if LAYER[_component(i)] > LAYER[_component(m)]]
    assert not upward, "\n".join(upward)


def test_nothing_in_the_library_imports_the_paper_reproduction():
    users = [m for m, edges in GRAPH.items() for i, _ in edges
             if _component(i) == "paper" and _component(m) != "paper"]
    assert not users, users


def test_no_import_cycles():
    """Tarjan's strongly connected components of the module graph: all of size one."""
    index, low, stack, on, cycles, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w, _ in GRAPH[v]:
            if w == v:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in GRAPH:
        if v not in index:
            visit(v)
    assert not cycles, cycles


def test_petsc_lives_in_one_layer():
    """petsc4py and mpi4py are imported only by linalg (options, linear solvers), the PETSc
    layer and the solving layer on it."""
    outside = [f"{m}:{ln} imports {i}" for m, p in MODULES.items() for i, ln in _imports(m, p)
               if i.split(".")[0] in ("petsc4py", "mpi4py") and _component(m) not in PETSC_COMPONENTS]
    assert not outside, "\n".join(outside)


def test_the_options_database_is_read_in_one_place():
    """PETSc's options database (``PETSc.Options()``) is read and written only by
    ``linalg/database.py`` (issue 29, point 5): the rest asks ``database.option``."""
    found = []
    for path in list(MODULES.values()) + [os.path.join(ROOT, "apps", f) for f in os.listdir(os.path.join(ROOT, "apps"))
                                          if f.endswith(".py")]:
        if os.path.relpath(path, PACKAGE) == os.path.join("linalg", "database.py"):
            continue
        for node in ast.walk(ast.parse(open(path).read())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "Options" \
                    and isinstance(node.func.value, ast.Name) and node.func.value.id == "PETSc":
                found.append(f"{os.path.relpath(path, ROOT)}:{node.lineno}")
    assert not found, found


def test_linear_solver_and_options_raise_input_errors_not_config_errors():
    """linalg and solving sit on errors.InputError, not on the config layer's ConfigError."""
    found = [f"{m}:{ln}" for m, p in MODULES.items() if _component(m) in ("linalg", "solving")
             for i, ln in _imports(m, p) if i == "ancf_petsc.config.values"]
    assert not found, found


def test_importing_the_package_loads_neither_petsc_nor_mpi():
    code = ("import sys, ancf_petsc; from ancf_petsc import config, physics, contact, model; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('petsc4py', 'mpi4py')))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                       env=dict(os.environ, PYTHONPATH=ROOT))
    assert p.returncode == 0 and p.stdout.strip() == "[]", p.stdout + p.stderr


@pytest.mark.parametrize("name", sorted(MODULES))
def test_small_pieces(name):
    """No module over 400 lines, no class over 250 (a design number: a class that does one job
    fits), no function over 60 without a stated reason."""
    path = MODULES[name]
    faults = _size_faults(open(path).read(), os.path.relpath(path, PACKAGE), LONG_FUNCTIONS)
    assert not faults, faults


def _size_faults(src: str, rel: str, long_functions: dict) -> list[str]:
    """A module over 400 lines, a class over 250, a function over 60 not in ``long_functions``."""
    out = [f"{rel}: {src.count(chr(10))} lines"] if src.count("\n") > 400 else []
    for node in ast.walk(ast.parse(src)):
        size = getattr(node, "end_lineno", 0) - getattr(node, "lineno", 0) + 1
        if isinstance(node, ast.ClassDef) and size > 250:
            out.append(f"{rel}: class {node.name} has {size} lines")
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and size > 60 \
                and f"{rel}:{node.name}" not in long_functions:
            out.append(f"{rel}: {node.name} has {size} lines")
    return out


def test_long_function_reasons_are_current():
    """Every listed long function still exists and is still long (else drop it from the list)."""
    for key in LONG_FUNCTIONS:
        rel, fn = key.split(":")
        tree = ast.parse(open(os.path.join(PACKAGE, rel)).read())
        sizes = [n.end_lineno - n.lineno + 1 for n in ast.walk(tree)
                 if isinstance(n, ast.FunctionDef) and n.name == fn]
        assert sizes and max(sizes) > 60, key


def test_scripts_do_not_import_tests():
    bad = []
    for f in os.listdir(os.path.join(ROOT, "scripts")):
        if f.endswith(".py"):
            tree = ast.parse(open(os.path.join(ROOT, "scripts", f)).read())
            for node in ast.walk(tree):
                names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                         [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
                bad += [f"{f}: {n}" for n in names if n.split(".")[0] in ("tests", "helpers", "conftest")]
    assert not bad, bad


def test_object_state_is_declared_in_init():
    """Every attribute a method sets (self.x = ...) is also set in __init__ (or is a dataclass field)."""
    late = []
    for name, path in MODULES.items():
        for cls in [n for n in ast.walk(ast.parse(open(path).read())) if isinstance(n, ast.ClassDef)]:
            declared = {st.target.id for st in cls.body
                        if isinstance(st, ast.AnnAssign) and isinstance(st.target, ast.Name)}
            set_in = {}
            for fn in [n for n in cls.body if isinstance(n, ast.FunctionDef)]:
                for node in ast.walk(fn):
                    targets = node.targets if isinstance(node, ast.Assign) else \
                        [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else []
                    for t in targets:
                        for x in ast.walk(t):
                            if isinstance(x, ast.Attribute) and isinstance(x.value, ast.Name) \
                                    and x.value.id == "self":
                                (declared.add(x.attr) if fn.name == "__init__"
                                 else set_in.setdefault(x.attr, fn.name))
            late += [f"{name}.{cls.name}.{a} (set in {m})" for a, m in set_in.items() if a not in declared]
    assert not late, late


# ------------------------------------------------------------------ failures as data (issue 29)
#: functions that read an exception's text, each with the reason no data field exists to read
#: instead (third-party messages only: the package's own failures carry path/message/kind,
#: reason codes and summary.json fields)
TEXT_READERS = {
    "io/files.py:os_reason": "h5py gives the errno only inside its message text",
    "linalg/diagnostics.py:petsc_message": "PETSc's error: the last line of its text is the reason",
    "yamlio.py:syntax_error": "PyYAML's first line when its error has no .problem",
}
_TEXT_METHODS = {"split", "rsplit", "splitlines", "startswith", "endswith", "find", "rfind", "index",
                 "partition", "rpartition", "count"}


def _failure_text(node: ast.AST, exc_names: set) -> bool:
    """``str(E)`` of an exception name E, or ``X.message`` (a failure's prose)."""
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "str" \
            and len(node.args) == 1 and isinstance(node.args[0], ast.Name) and node.args[0].id in exc_names:
        return True
    return isinstance(node, ast.Attribute) and node.attr == "message"


def _text_reads(tree: ast.AST) -> list[tuple[str, int, str]]:
    """(function, line, what) of every place a failure is read back from its text: a substring
    test on ``str(exc)`` / ``.message``, a string method or a regex on them, or a line of the
    program's own output recognised by its ``ancf-...`` prefix."""
    out = []
    for fn in [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]:
        exc_names = {h.name for h in ast.walk(fn) if isinstance(h, ast.ExceptHandler) and h.name}
        exc_names |= {"exc", "err", "error"}
        for node in ast.walk(fn):
            what = None
            if isinstance(node, ast.Compare) and any(isinstance(o, (ast.In, ast.NotIn)) for o in node.ops) \
                    and any(_failure_text(c, exc_names) for c in node.comparators):
                what = "a substring test"
            elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
                f = node.func
                if f.attr in _TEXT_METHODS and _failure_text(f.value, exc_names):
                    what = f".{f.attr}()"
                elif isinstance(f.value, ast.Name) and f.value.id == "re" \
                        and any(_failure_text(a, exc_names) for a in node.args):
                    what = f"re.{f.attr}()"
                elif f.attr in ("startswith", "endswith", "find") and node.args \
                        and isinstance(node.args[0], ast.Constant) and str(node.args[0].value).startswith("ancf-"):
                    what = "a line of the program's own output"
            if what:
                out.append((fn.name, node.lineno, what))
    return out


def test_failures_are_read_as_data_not_text():
    """No ``in str(exc)``, ``str(exc).split``, regex over a message or over ancf-solve's stderr:
    read ``InputError.path/message/kind``, reason codes and summary.json instead."""
    found = []
    for name, path in MODULES.items():
        rel = os.path.relpath(path, PACKAGE)
        found += [f"{rel}:{fn}:{ln}: {what}" for fn, ln, what in _text_reads(ast.parse(open(path).read()))
                  if f"{rel}:{fn}" not in TEXT_READERS]
    assert not found, "\n".join(found)


def test_text_reader_exceptions_are_current():
    for key in TEXT_READERS:
        rel, fn = key.split(":")
        assert fn in {f for f, _, _ in _text_reads(ast.parse(open(os.path.join(PACKAGE, rel)).read()))}, key


def test_the_text_rule_catches_what_it_forbids():
    src = ("def f(run):\n"
           "    try:\n        g()\n    except ValueError as exc:\n"
           "        if 'unknown key' in str(exc): pass\n"
           "        a = str(exc).split(': ', 1)[1]\n"
           "        re.search('x', str(exc))\n"
           "    if '\\n' not in run.message: pass\n"
           "    [ln for ln in lines if ln.startswith('ancf-solve:')]\n")
    assert len(_text_reads(ast.parse(src))) == 5


# ------------------------------------------------------------ one registry per vocabulary (issue 29)
def _vocabularies() -> dict[str, tuple[set, set]]:
    """vocabulary → (its names, read from the registry; the modules that own them)."""
    from ancf_petsc.contact.laws import LAWS
    from ancf_petsc.physics.elements import ELEMENTS
    from ancf_petsc.physics.laws import MATERIALS
    from ancf_petsc.contact.tangential import TANGENTIAL_LAWS
    from ancf_petsc.outline_formats import FORMATS
    tangential = {name for name, cls in TANGENTIAL_LAWS.items() if cls is not None}   # not "none"
    return {"contact law": (set(LAWS), {"contact/laws.py"}),
            "geometry importer": (set(FORMATS), OUTLINE_FORMAT_MODULES),
            "tangential law": (tangential, {"contact/tangential.py", "contact/elastic_interface.py",
                                            "contact/friction.py"}),
            "element": (set(ELEMENTS), ELEMENT_MODULES),
            "material": (set(MATERIALS), {"physics/laws.py", "physics/materials.py", "physics/goh.py"})}


def _spelt(tree: ast.AST, names: set) -> list[tuple[int, str]]:
    """(line, what) of every ``== "name"`` / ``in ("a", "b")`` test on a registry name and every
    literal list that spells two or more of them (a second copy of the vocabulary)."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and any(isinstance(o, (ast.Eq, ast.NotEq, ast.In, ast.NotIn))
                                                 for o in node.ops):
            for x in [node.left] + node.comparators:
                if isinstance(x, ast.Constant) and x.value in names:
                    out.append((node.lineno, f"compares with {x.value!r}"))
        elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            hits = [e.value for e in node.elts
                    if isinstance(e, ast.Constant) and isinstance(e.value, str) and e.value in names]
            if len(hits) >= 2:
                out.append((node.lineno, f"spells the vocabulary {hits}"))
    return out


#: the modules of the element registry (one per element, plus the registry and its types)
ELEMENT_MODULES = {os.path.relpath(p, PACKAGE) for m, p in MODULES.items()
                   if os.path.relpath(p, PACKAGE).startswith("physics/elements/")}


def test_registry_names_are_not_spelt_outside_their_module():
    """Contact laws (contact/laws.py LAWS), elements (physics/elements ELEMENTS),
    materials (physics/laws.py MATERIALS) and geometry importers (outline_formats FORMATS)
    are named in code only by their registry: no
    ``law == "unilateral"`` or ``("3363", "3333")`` elsewhere; behaviour lives in the law,
    element or material (e.g. ``ElementType.default_locking``)."""
    found = []
    for what, (names, owners) in _vocabularies().items():
        for name, path in MODULES.items():
            rel = os.path.relpath(path, PACKAGE)
            if rel not in owners:
                found += [f"{rel}:{ln}: {what}: {msg}" for ln, msg in _spelt(ast.parse(open(path).read()), names)]
    assert not found, "\n".join(found)


#: the modules of the outline-format registry (one per format, plus their shared helpers)
OUTLINE_FORMAT_MODULES = {os.path.relpath(p, PACKAGE) for m, p in MODULES.items()
                          if _component(m) == "outline_formats"}


def _extensions_spelt(tree: ast.AST, extensions: set) -> list[tuple[int, str]]:
    """(line, what) of every outline file extension in a literal list, an ``endswith`` /
    ``startswith`` or a comparison: a second copy of the extension → format table."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            elts = node.elts
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                and node.func.attr in ("endswith", "startswith"):
            elts = node.args
        elif isinstance(node, ast.Compare):
            elts = [node.left] + node.comparators
        else:
            continue
        hits = [e.value for e in elts if isinstance(e, ast.Constant) and isinstance(e.value, str)
                and e.value.lower() in extensions]
        if hits:
            out.append((node.lineno, f"spells the outline file extension(s) {hits}"))
    return out


def test_outline_formats_are_named_only_by_their_registry():
    """A geometry importer is one module of ``outline_formats/``: no format name
    (``kind == "nifti"``) and no extension (``endswith((".nii", ".nii.gz"))``) anywhere else;
    config validation, the build and the docs read ``FORMATS``."""
    from ancf_petsc.outline_formats import FORMATS
    extensions = {e for f in FORMATS.values() for e in f.extensions}
    found = []
    for name, path in MODULES.items():
        rel = os.path.relpath(path, PACKAGE)
        if rel not in OUTLINE_FORMAT_MODULES:
            found += [f"{rel}:{ln}: {msg}" for ln, msg in _extensions_spelt(ast.parse(open(path).read()), extensions)]
    assert not found, "\n".join(found)
    src = ('if low.endswith((".nii", ".nii.gz")): kind = "nifti"\n'
           'POINT_EXT = (".csv", ".txt")\nif kind in ("svg", "nifti"): pass\nif ext == ".svg": pass\n'
           'mask = name.endswith(".png")\n')
    tree = ast.parse(src)
    assert len(_extensions_spelt(tree, extensions)) == 4 and len(_spelt(tree, set(FORMATS))) == 1


def test_every_outline_format_module_registers_one_importer():
    """Each module of ``outline_formats/`` binds ``IMPORTER`` (a format) or is a helper that
    defines none; the registry holds exactly the modules' importers, with their extensions
    claimed once and their keys typed."""
    import importlib
    from ancf_petsc.outline_formats import FORMATS, Importer
    bound = []
    for m in MODULES:
        if _component(m) == "outline_formats" and m.count(".") == 2:
            imp = getattr(importlib.import_module(m), "IMPORTER", None)
            if imp is not None:
                bound.append(imp)
    assert sorted(f.name for f in bound) == sorted(FORMATS) and all(isinstance(f, Importer) for f in bound)
    exts = [e for f in FORMATS.values() for e in f.extensions]
    assert len(exts) == len(set(exts)) and all(e.startswith(".") and e == e.lower() for e in exts)
    assert all(k.type in (int, str) for f in FORMATS.values() for k in f.keys)


def _field_lists(tree: ast.AST, names: set) -> list[tuple[int, str]]:
    """(line, what) of every literal list, tuple, set or dict (keys) that spells two or more
    output field names: a second copy of the field vocabulary (single names are also config
    keys, e.g. a support's ``displacement``, and are not counted)."""
    out = [(ln, msg) for ln, msg in _spelt(tree, names) if msg.startswith("spells")]
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            hits = [k.value for k in node.keys if isinstance(k, ast.Constant) and k.value in names]
            if len(hits) >= 2:
                out.append((node.lineno, f"spells the vocabulary {hits} as keys"))
    return out


def test_output_fields_are_listed_only_by_their_registry():
    """The surface VTU's point fields (io/surface_fields.py SURFACE_FIELDS: label, unit, factor,
    the function, where it applies) are listed nowhere else: no label table in viz, no
    ``{"displacement": [], "E_xx": [], ...}`` in the writer."""
    from ancf_petsc.io.surface_fields import SURFACE_FIELDS
    names = set(SURFACE_FIELDS)
    found = []
    for name, path in MODULES.items():
        rel = os.path.relpath(path, PACKAGE)
        if rel != "io/surface_fields.py":
            found += [f"{rel}:{ln}: {msg}" for ln, msg in _field_lists(ast.parse(open(path).read()), names)]
    assert not found, "\n".join(found)
    old = ('FIELD_LABELS = {"E_xx": ("strain", "%", 100.0), "J": ("J", "-", 1.0)}\n'
           'data = {"displacement": [], "E_xx": [], "J": [], "beam": []}\n'
           'if mode == "displacement": pass\n')
    assert len(_field_lists(ast.parse(old), names)) == 2


def test_config_vocabularies_are_the_registries():
    from ancf_petsc.config.beams import MATERIAL_PARSERS
    from ancf_petsc.config.contact import TANGENTIAL_PARSERS
    from ancf_petsc.config.specs import CONTACT_MODES, MATERIAL_MODELS, TANGENTIAL_LAW_NAMES
    from ancf_petsc.contact.tangential import TANGENTIAL_LAWS
    from ancf_petsc.contact.laws import LAWS
    from ancf_petsc.physics.elements import ELEMENTS, element_names
    from ancf_petsc.physics.laws import MATERIALS
    from ancf_petsc.config.sections import OUTLINE_KEYS
    from ancf_petsc.outline_formats import FORMATS
    assert set(OUTLINE_KEYS) == {"points", "file", "curves"} | {k.name for f in FORMATS.values() for k in f.keys}
    assert CONTACT_MODES == tuple(LAWS) and MATERIAL_MODELS == tuple(MATERIALS)
    assert TANGENTIAL_LAW_NAMES == tuple(TANGENTIAL_LAWS)
    assert set(TANGENTIAL_PARSERS) == {n for n, cls in TANGENTIAL_LAWS.items() if cls is not None}
    assert set(MATERIAL_PARSERS) == set(MATERIALS) and element_names() == tuple(ELEMENTS)
    assert all(e.name == name for name, e in ELEMENTS.items())


# ---------------------------------------------------------------- public names (issue 29, point 7)
def test_every_package_declares_its_public_names():
    """``__all__`` in every package ``__init__``; each entry is a name the ``__init__`` binds
    or a sub-module of the package."""
    bad = []
    for name, path in MODULES.items():
        if not path.endswith("__init__.py"):
            continue
        tree = ast.parse(open(path).read())
        declared = [n for n in tree.body if isinstance(n, ast.Assign)
                    and any(isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets)]
        if not declared:
            bad.append(f"{name}: no __all__")
            continue
        bound = {a.asname or a.name for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))
                 for a in n.names}
        bound |= {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
        bound |= {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
        here = os.path.dirname(path)
        try:
            entries = ast.literal_eval(declared[0].value)
        except ValueError:                  # the root package: names served lazily (PEP 562)
            continue
        for entry in entries:
            if entry not in bound and not os.path.exists(os.path.join(here, entry + ".py")) \
                    and not os.path.exists(os.path.join(here, entry, "__init__.py")):
                bad.append(f"{name}: __all__ names {entry!r}, which it neither binds nor has as a module")
    assert not bad, "\n".join(bad)


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def test_no_private_name_is_imported_from_another_module():
    """``from .x import _y`` (or ``x._y`` on an imported module) reaches into another module's
    insides: make ``_y`` public (it is shared) or keep it where it is used."""
    bad = []
    for name, path in MODULES.items():
        rel = os.path.relpath(path, PACKAGE)
        tree = ast.parse(open(path).read())
        modules = {a.asname or a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                   for a in node.names if _is_package_module(name, path, node, a.name)}
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                bad += [f"{rel}:{node.lineno}: imports {a.name}" for a in node.names if _private(a.name)]
            elif isinstance(node, ast.Attribute) and _private(node.attr) and isinstance(node.value, ast.Name) \
                    and node.value.id in modules:
                bad.append(f"{rel}:{node.lineno}: reads {node.value.id}.{node.attr}")
    assert not bad, "\n".join(bad)


def _is_package_module(name: str, path: str, node: ast.ImportFrom, imported: str) -> bool:
    """``from <package> import <imported>`` names one of the package's own modules."""
    return any(i.endswith("." + imported) and i in MODULES
               for i, ln in _imports(name, path) if ln == node.lineno)


# ------------------------------------------- scripts and the verification package (issue 41)
SCRIPTS = os.path.join(ROOT, "scripts")
SCRIPT_NAMES = sorted(f[:-3] for f in os.listdir(SCRIPTS) if f.endswith(".py"))
VERIFY = os.path.join(ROOT, "ancf_verify")
#: a thin command line: at most this many lines, no def or class, nothing at module level but its
#: docstring, imports, ``sys.path.insert`` and ``if __name__ == "__main__":``
THIN_LINES = 20
#: scripts that are not yet thin command lines, each with the line count it may not exceed (a
#: ratchet: lower a number when a script shrinks, drop it when the script is thin).  None is left
#: (2026-11-28): issue 41 moved the 3D solids, the benchmarks and the beam studies into ancf_verify.
NOT_YET_THIN: dict[str, int] = {}
#: ancf_verify functions longer than 60 lines, each with the reason it stays in one piece
VERIFY_LONG_FUNCTIONS = {
    "fibres/report.py:render_block": "one generated block of docs/fibres.md, in reading order",
    "bars/report.py:render_md": "one page (docs/solid_comparison.md), in reading order",
    "bars/solid.py:solve_solid": "one dolfinx solve: space, forms, boundary conditions, load steps",
    "cli/contact.py:main": "the options, then the study's steps in the order they run",
    "cli/friction.py:main": "the options, then the study's steps in the order they run",
    "contact/report.py:render_md": "one page (docs/solid_contact.md), section by section in reading order",
    "contact/selftest.py:selftest_blocks": "one patch test: two blocks, their contact and the checks",
    "contact/selftest.py:selftest_fd": "one finite-difference check of the contact tangent",
    "contact/mesh.py:gmsh_body": "one gmsh body: outline, extrusion, layers and physical groups",
    "contact/bodies.py:__init__": "the bodies' spaces, forms and interfaces set up in dependency order",
    "contact/newton.py:newton": "one Newton iteration loop with its contact-set and stall tests",
    "friction/page.py:section": "one generated section of docs/interface.md, in reading order",
}


def _script_tree(name: str) -> ast.Module:
    return ast.parse(open(os.path.join(SCRIPTS, name + ".py")).read())


def _imported(tree: ast.AST) -> list[tuple[str, int]]:
    """(top-level module name, line) of every import, also inside functions."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name.split(".")[0], node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and not node.level:
            out.append(((node.module or "").split(".")[0], node.lineno))
    return out


def test_scripts_import_no_other_script():
    bad = [f"scripts/{s}.py:{ln} imports {m}" for s in SCRIPT_NAMES for m, ln in _imported(_script_tree(s))
           if m in SCRIPT_NAMES]
    assert not bad, "\n".join(bad)


def _is_thin(tree: ast.Module) -> list[str]:
    """What keeps a script from being a thin command line (empty: it is one)."""
    why = []
    for i, node in enumerate(tree.body):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        if i == 0 and isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            continue                                                  # the docstring
        if isinstance(node, ast.Expr) and ast.unparse(node).startswith("sys.path.insert("):
            continue
        if isinstance(node, ast.If) and ast.unparse(node.test) == "__name__ == '__main__'" \
                and all(isinstance(n, (ast.Expr, ast.Raise)) for n in node.body) and len(node.body) == 1:
            continue
        why.append(f"line {node.lineno}: {type(node).__name__}")
    return why


@pytest.mark.parametrize("name", SCRIPT_NAMES)
def test_scripts_are_thin_command_lines(name):
    """Every script is a thin command line over a package (ancf_verify.cli, ancf_petsc's apps)
    or, for the scripts not yet moved, no longer than its entry in NOT_YET_THIN."""
    src = open(os.path.join(SCRIPTS, name + ".py")).read()
    lines = src.count("\n")
    if name in NOT_YET_THIN:
        assert lines <= NOT_YET_THIN[name], f"scripts/{name}.py grew to {lines} lines (budget {NOT_YET_THIN[name]})"
        assert _is_thin(ast.parse(src)), f"scripts/{name}.py is thin now: drop it from NOT_YET_THIN"
        return
    why = _is_thin(ast.parse(src))
    assert lines <= THIN_LINES and not why, f"scripts/{name}.py ({lines} lines) is not a thin command line: {why}"


def test_the_thin_rule_can_fail():
    fat = ast.parse('"""doc"""\nimport sys\nX = 1\ndef main():\n    pass\nif __name__ == "__main__":\n    main()\n')
    thin = ast.parse('"""doc"""\nimport sys\nsys.path.insert(0, "x")\nfrom a import run\n'
                     'if __name__ == "__main__":\n    sys.exit(run("c", "n"))\n')
    assert len(_is_thin(fat)) == 2 and not _is_thin(thin)
    assert set(NOT_YET_THIN) <= set(SCRIPT_NAMES), set(NOT_YET_THIN) - set(SCRIPT_NAMES)


VERIFY_MODULES = _modules(VERIFY)


def _monkeypatches(tree: ast.Module) -> list[tuple[int, str]]:
    """(line, target) of every assignment to an attribute of an imported name (a module or one of
    its classes or functions) and every ``setattr`` on one: replacing another module's insides."""
    imported = {a.asname or a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))
                for a in n.names}
    out = []
    for node in ast.walk(tree):
        targets = node.targets if isinstance(node, ast.Assign) else \
            [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else []
        for t in targets:
            base = t
            while isinstance(base, ast.Attribute):
                base = base.value
            if isinstance(t, ast.Attribute) and isinstance(base, ast.Name) and base.id in imported:
                out.append((node.lineno, ast.unparse(t)))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "setattr" \
                and node.args and isinstance(node.args[0], ast.Name) and node.args[0].id in imported:
            out.append((node.lineno, f"setattr({node.args[0].id}, ...)"))
    return out


def test_nothing_monkeypatches_another_module():
    """Neither scripts/ nor ancf_verify replaces a function, class attribute or constant of
    another module: what a study needs to change is an option (e.g. ContactSpec.group,
    BeamSpec.volumetric_degree, TangentialSpec.free_zone)."""
    paths = [os.path.join(SCRIPTS, s + ".py") for s in SCRIPT_NAMES] + list(VERIFY_MODULES.values())
    bad = [f"{os.path.relpath(p, ROOT)}:{ln}: {t}" for p in paths for ln, t in _monkeypatches(ast.parse(open(p).read()))]
    assert not bad, "\n".join(bad)
    old = ("import ancf_petsc.model.beams as beams\nfrom ancf_petsc.physics import goh\n"
           "from ancf_petsc.contact.friction import CoulombFriction\n"
           "beams.pressure_basis = f\ngoh.E_ROUNDING = 0.0\nCoulombFriction.evaluate = g\n"
           "setattr(goh, 'E_ROUNDING', 1)\nself.x = 1\nspec.contact.group = 4\n")
    assert [t for _, t in _monkeypatches(ast.parse(old))] == [
        "beams.pressure_basis", "goh.E_ROUNDING", "CoulombFriction.evaluate", "setattr(goh, ...)"]


def test_the_library_never_imports_the_verification_package():
    paths = list(MODULES.values()) + [os.path.join(ROOT, "apps", f) for f in os.listdir(os.path.join(ROOT, "apps"))
                                      if f.endswith(".py")]
    bad = [f"{os.path.relpath(p, ROOT)}:{ln}" for p in paths for m, ln in _imported(ast.parse(open(p).read()))
           if m == "ancf_verify"]
    assert not bad, bad


def _verify_graph() -> dict[str, list[str]]:
    graph = {}
    for name, path in VERIFY_MODULES.items():
        tree = ast.parse(open(path).read())
        edges = []
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("ancf_verify"):
                for a in node.names:
                    sub = f"{node.module}.{a.name}"
                    edges.append(sub if sub in VERIFY_MODULES else node.module)
            elif isinstance(node, ast.Import):
                edges += [a.name for a in node.names if a.name in VERIFY_MODULES]
        graph[name] = [e for e in edges if e in VERIFY_MODULES and e != name]
    return graph


def test_the_verification_package_has_no_import_cycles():
    graph, state, cycles = _verify_graph(), {}, []

    def visit(v, path):
        state[v] = 1
        for w in graph[v]:
            if state.get(w) == 1:
                cycles.append(path[path.index(w):] + [w])
            elif w not in state:
                visit(w, path + [w])
        state[v] = 2
    for v in graph:
        if v not in state:
            visit(v, [v])
    assert not cycles, cycles


@pytest.mark.parametrize("name", sorted(VERIFY_MODULES))
def test_verification_modules_are_small_pieces(name):
    """The library's size rules (``test_small_pieces``) hold in ancf_verify too, and every module
    has a docstring."""
    path = VERIFY_MODULES[name]
    src = open(path).read()
    rel = os.path.relpath(path, VERIFY)
    assert ast.get_docstring(ast.parse(src)), f"{rel}: no module docstring"
    faults = _size_faults(src, rel, VERIFY_LONG_FUNCTIONS)
    assert not faults, faults


def test_verification_long_function_reasons_are_current():
    for key in VERIFY_LONG_FUNCTIONS:
        rel, fn = key.split(":")
        tree = ast.parse(open(os.path.join(VERIFY, rel)).read())
        sizes = [n.end_lineno - n.lineno + 1 for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name == fn]
        assert sizes and max(sizes) > 60, key
