"""The package's floors (README, "How it fits together"): a module imports only from its own floor or lower ones,
and no modules import each other in a loop. Read from the source with `ast`, function-local imports included."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "dexguitar"
FLOORS = ["errors", "shipped", "world", "music", "planner", "envs", "motion", "learn", "configs", "perform", "cli"]   # `dexguitar` itself: floor 0


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def floor(module: str) -> int:
    parts = module.split(".")
    return 0 if len(parts) == 1 else FLOORS.index(parts[1])


def imports() -> dict[str, set[str]]:
    """module -> the package modules it imports (a `from package import module` counts as the module)."""
    modules = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        found = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                found |= {a.name for a in node.names if a.name.startswith("dexguitar")}
            elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("dexguitar"):
                found |= {f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in modules else node.module
                          for a in node.names}
        graph[name] = {m for m in found if m != name}
    return graph


def test_imports_only_go_down_the_floors():
    bad = [f"{m} (floor {FLOORS[floor(m)] if floor(m) else 'dexguitar'}) imports {i} ({FLOORS[floor(i)]})"
           for m, deps in imports().items() for i in deps if floor(i) > floor(m)]
    assert not bad, "\n".join(bad)


def test_no_import_cycles():
    graph = imports()
    state, cycles = {}, []

    def visit(m, stack):
        state[m] = "open"
        for d in sorted(graph.get(m, ())):
            if state.get(d) == "open":
                cycles.append(" -> ".join(stack[stack.index(d):] + [d]))
            elif d not in state:
                visit(d, stack + [d])
        state[m] = "done"
    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not cycles, "\n".join(cycles)


def test_the_check_sees_the_floors():
    # the check would catch a violation: the envs floor really imports music and world, and the CLI everything
    graph = imports()
    assert "dexguitar.music.cursor" in graph["dexguitar.envs.core"]
    assert floor("dexguitar.envs.core") > floor("dexguitar.music.cursor") > floor("dexguitar.world.guitar")
    # the envs attach the planner's plans themselves, and the planner needs nothing above it
    assert "dexguitar.planner" in graph["dexguitar.envs"]
    assert max(floor(m) for p in graph if p.startswith("dexguitar.planner") for m in graph[p]) < floor("dexguitar.envs")
    assert {floor(m) for m in graph["dexguitar.cli"]} >= {FLOORS.index(f) for f in ("music", "envs", "motion", "learn", "configs", "perform")}
