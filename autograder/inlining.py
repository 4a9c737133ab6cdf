"""The students' copy of a routine that draws with a graded function the wheel leaves out.

A figure or an explorer may need the maths of a graded function whose reference the students'
wheel must not hold in any callable form (docs/students-copy.md). Such a routine is listed in
:data:`autograder.student_bundle.INLINE_INTO`; it returns only a whole figure, an 8-bit image,
text, or numbers at display precision. Its students' copy calls a **C-level copy** of each
left-out function it needs: Cython's pure-Python mode compiles a ``def`` decorated with
``@cython.cfunc`` into a static C function with no Python object, so the copy is in no
module's namespace and on no garbage-collector list, and only the compiled code of its own
module can call it (the wheel's binaries are stripped of symbol names too).

:func:`inline_into` rewrites a module's source so: each listed routine's calls of left-out
functions (``phong(...)``, ``shading.phong(...)``, ``from .shading import phong``) go to private
copies named ``_<module>__<function>`` (dots as underscores) added to the module; the copies
of functions from another module read that module's globals through private imports. A
left-out function named any other way (as a value, with ``*args``, outside a listed routine)
is refused with a ``ValueError`` naming the place, as is a left-out function a C function
cannot be (decorated, ``*args``/``**kwargs``, a generator, ``global`` statements).
"""

from __future__ import annotations

import ast
import copy
import symtable
from collections.abc import Callable

#: the decorator that makes a pure-Python ``def`` a C-level function when Cython compiles it
CFUNC = "cython.cfunc"


def c_name(module: str, name: str) -> str:
    """The private name of ``module.name``'s C-level copy, e.g. ``_course_lib_shading__phong``."""
    return f"_{module.replace('.', '_')}__{name}"


def _alias_name(module: str, name: str) -> str:
    return f"_from_{module.replace('.', '_')}__{name}"


class _Module:
    """A library module's source with what its names resolve to."""

    def __init__(self, name: str, text: str, is_module: Callable[[str], bool]):
        self.name, self.text = name, text
        self.tree = ast.parse(text)
        self.modules: dict[str, str] = {}          # local alias -> dotted module
        self.imported: dict[str, tuple[str, str]] = {}   # local name -> (module, name)
        package = name.rpartition(".")[0]
        for node in ast.walk(self.tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.asname:
                        self.modules[a.asname] = a.name
                    else:
                        root = a.name.partition(".")[0]
                        self.modules[root] = root
            elif isinstance(node, ast.ImportFrom):
                base = _absolute(node, package)
                for a in node.names:
                    local = a.asname or a.name
                    if is_module(f"{base}.{a.name}"):
                        self.modules[local] = f"{base}.{a.name}"
                    else:
                        self.imported[local] = (base, a.name)
        self.top = {n.name: n for n in self.tree.body
                    if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))}

    def resolve(self, node: ast.AST) -> tuple[str, str] | None:
        """``(module, name)`` that a ``Name`` or dotted ``Attribute`` refers to, if known."""
        if isinstance(node, ast.Name):
            if node.id in self.imported:
                return self.imported[node.id]
            if node.id in self.top:
                return (self.name, node.id)
            return None
        parts = []
        while isinstance(node, ast.Attribute):
            parts.append(node.attr)
            node = node.value
        if not isinstance(node, ast.Name) or node.id not in self.modules:
            return None
        dotted = ".".join([self.modules[node.id]] + parts[::-1][:-1])
        return (dotted, parts[0])

    def find(self, qualname: str) -> ast.FunctionDef:
        scope, node = self.tree.body, None
        for part in qualname.split("."):
            node = next((n for n in scope if isinstance(n, (ast.FunctionDef, ast.ClassDef))
                         and n.name == part), None)
            if node is None:
                raise ValueError(f"{self.name} has no {qualname} to inline into")
            scope = node.body
        if not isinstance(node, ast.FunctionDef):
            raise ValueError(f"{self.name}.{qualname} is not a function")
        return node


def _absolute(node: ast.ImportFrom, package: str) -> str:
    if not node.level:
        return node.module or ""
    parts = package.split(".")
    parts = parts[:len(parts) - node.level + 1]
    return ".".join(parts + ([node.module] if node.module else []))


class _Redirect(ast.NodeTransformer):
    """Sends a function's calls of left-out functions to their C-level copies; refuses any
    other use of a left-out function. ``found`` collects ``(module, name)`` called."""

    def __init__(self, mod: _Module, left: dict[str, tuple[str, ...]], where: str):
        self.mod, self.left, self.where = mod, left, where
        self.found: set[tuple[str, str]] = set()
        self.calls: list[tuple[ast.Call, tuple[str, str]]] = []

    def _target(self, node):
        hit = self.mod.resolve(node)
        return hit if hit and hit[1] in self.left.get(hit[0], ()) else None

    def visit_Call(self, node: ast.Call):
        hit = self._target(node.func)
        if hit:
            if any(isinstance(a, ast.Starred) for a in node.args) or any(
                    k.arg is None for k in node.keywords):
                raise ValueError(f"{self.where} calls {hit[0]}.{hit[1]} with *args or **kwargs "
                                 "(write its arguments out)")
            self.found.add(hit)
            self.calls.append((node, hit))
            node.func = ast.copy_location(ast.Name(c_name(*hit), ast.Load()), node.func)
            node.args = [self.visit(a) for a in node.args]
            node.keywords = [self.visit(k) for k in node.keywords]
            return node
        return self.generic_visit(node)

    def _refuse(self, node):
        hit = self._target(node)
        if hit:
            raise ValueError(f"{self.where} uses {hit[0]}.{hit[1]} other than by calling it "
                             "(the students' copy holds it only as a C function)")
        return self.generic_visit(node)

    visit_Name = _refuse
    visit_Attribute = _refuse


def _check_c_function(node: ast.FunctionDef, where: str):
    a = node.args
    if node.decorator_list or a.vararg or a.kwarg:
        raise ValueError(f"{where} cannot be a C function (decorators, *args or **kwargs)")
    todo = list(node.body)
    while todo:     # its own scope only: a nested function may yield
        sub = todo.pop()
        if isinstance(sub, (ast.Yield, ast.YieldFrom, ast.Global, ast.Nonlocal)):
            raise ValueError(f"{where} cannot be a C function (yield, global or nonlocal)")
        if not isinstance(sub, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            todo.extend(ast.iter_child_nodes(sub))


def _globals_of(text: str, module: str, name: str) -> tuple[set[str], set[str]]:
    """Names function ``name`` of ``text`` (and the scopes within it) reads as globals, and
    the names bound locally anywhere in it."""
    table = next(t for t in symtable.symtable(text, module, "exec").get_children()
                 if t.get_name() == name and t.get_type() == "function")
    glob, local, todo = set(), set(), [table]
    while todo:
        t = todo.pop()
        for sym in t.get_symbols():
            if sym.is_global() and not sym.is_declared_global():
                glob.add(sym.get_name())
            elif sym.is_local() or sym.is_parameter():
                local.add(sym.get_name())
        todo.extend(t.get_children())
    return glob, local


class _Rename(ast.NodeTransformer):
    def __init__(self, names: dict[str, str]):
        self.names = names

    def visit_Name(self, node: ast.Name):
        if node.id in self.names:
            return ast.copy_location(ast.Name(self.names[node.id], node.ctx), node)
        return node


def _c_copy(mod: _Module, name: str, here: str, left, aliases: dict) -> tuple[ast.FunctionDef,
                                                                             _Redirect]:
    """The C-level copy of ``mod.name`` for module ``here``, and what it calls in turn."""
    where = f"{mod.name}.{name}"
    node = mod.top.get(name)
    if not isinstance(node, ast.FunctionDef):
        raise ValueError(f"{where} is not a top-level function")
    _check_c_function(node, where)
    node = copy.deepcopy(node)
    redirect = _Redirect(mod, left, where)
    node = redirect.visit(node)
    if mod.name != here:   # its globals live in its own module: read them through imports
        glob, local = _globals_of(mod.text, mod.name, name)
        bound = _top_bindings(mod.tree)
        glob = {g for g in glob if g in bound} - set(left.get(mod.name, ()))
        clash = sorted(glob & local)
        if clash:
            raise ValueError(f"{where} uses {clash} both as globals and as locals")
        renames = {g: _alias_name(mod.name, g) for g in glob}
        aliases.update({(mod.name, g): a for g, a in renames.items()})
        node = _Rename(renames).visit(node)
    # no defaults: a default may name its own module's globals, and every call of a copy
    # passes every argument (:func:`_fill_defaults`)
    node.args.defaults = []
    node.args.kw_defaults = [None] * len(node.args.kwonlyargs)
    node.name = c_name(mod.name, name)
    node.decorator_list = [ast.Attribute(ast.Name("cython", ast.Load()), "cfunc", ast.Load())]
    return node, redirect


def _fill_defaults(call: ast.Call, home: _Module, name: str, here: str, aliases: dict):
    """Pass every parameter ``call`` leaves to its default explicitly: a C function's call
    cannot skip an optional argument and give a later one (Cython: "missing argument")."""
    sig = home.top[name].args
    positional = sig.posonlyargs + sig.args
    given = {k.arg for k in call.keywords} | {a.arg for a in positional[:len(call.args)]}
    defaults = dict(zip([a.arg for a in positional[len(positional) - len(sig.defaults):]],
                        sig.defaults))
    defaults.update({a.arg: d for a, d in zip(sig.kwonlyargs, sig.kw_defaults) if d is not None})
    bound = _top_bindings(home.tree)
    for param, default in defaults.items():
        if param in given:
            continue
        value = copy.deepcopy(default)
        if home.name != here:   # a default naming its module's globals reads them by import
            names = {n.id for n in ast.walk(value) if isinstance(n, ast.Name)} & bound
            renames = {g: _alias_name(home.name, g) for g in names}
            aliases.update({(home.name, g): a for g, a in renames.items()})
            value = _Rename(renames).visit(value)
        call.keywords.append(ast.keyword(param, value))


def _top_bindings(tree: ast.Module) -> set[str]:
    bound = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            bound.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            bound.update((a.asname or a.name).partition(".")[0] for a in node.names)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                bound.update(n.id for n in ast.walk(t) if isinstance(n, ast.Name))
    return bound


def inline_into(text: str, module: str, routines, left: dict[str, tuple[str, ...]],
                source_of: Callable[[str], str], is_module: Callable[[str], bool]) -> str:
    """``module``'s source ``text`` with each routine of ``routines`` (qualified names) calling
    C-level copies of the left-out functions (``left``: ``{module: names}``) it calls,
    directly or through another copy. ``source_of(m)`` gives library module ``m``'s source
    (the instructors' text); ``is_module(dotted)`` says whether a dotted name is a module.

    The left-out functions of ``module`` itself are left in place for the caller to remove.
    """
    if not routines:
        return text
    here = _Module(module, text, is_module)
    todo: set[tuple[str, str]] = set()
    calls = []
    for qualname in routines:
        redirect = _Redirect(here, left, f"{module}.{qualname}")
        redirect.visit(here.find(qualname))
        todo |= redirect.found
        calls += redirect.calls
    if not todo:
        raise ValueError(f"{module}: {sorted(routines)} call no left-out function "
                         "(take them out of INLINE_INTO)")
    parsed = {module: here}
    copies, done, aliases = [], set(), {}
    while todo:
        target = min(todo)
        todo.discard(target)
        done.add(target)
        home = target[0]
        if home not in parsed:
            parsed[home] = _Module(home, source_of(home), is_module)
        node, redirect = _c_copy(parsed[home], target[1], module, left, aliases)
        copies.append(node)
        todo |= redirect.found - done
        calls += redirect.calls
    for call, (home, name) in calls:
        _fill_defaults(call, parsed[home], name, module, aliases)
    _drop_imported(here, left)
    head = [ast.Import([ast.alias("cython")])]
    head += [ast.ImportFrom(m, [ast.alias(g, a)], 0) for (m, g), a in sorted(aliases.items())]
    at = max((i + 1 for i, n in enumerate(here.tree.body)
              if isinstance(n, (ast.Import, ast.ImportFrom))), default=0)
    here.tree.body[at:at] = head + sorted(copies, key=lambda n: n.name)
    return ast.unparse(ast.fix_missing_locations(here.tree)) + "\n"


def _drop_imported(mod: _Module, left):
    """Remove ``from m import f`` of left-out functions from the module's top level."""
    body = []
    for node in mod.tree.body:
        if isinstance(node, ast.ImportFrom):
            node.names = [a for a in node.names
                          if (mod.imported.get(a.asname or a.name, ("", ""))[1]
                              not in left.get(mod.imported.get(a.asname or a.name,
                                                               ("", ""))[0], ()))]
            if not node.names:
                continue
        body.append(node)
    mod.tree.body = body
