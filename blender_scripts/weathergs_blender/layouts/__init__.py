"""Scene layouts, one module per scene type: the module's name is the type, its build(b, p, rng) builds
the scene with a Builder b from the layout parameters p. The set of modules in this folder is the one
list of scene types (capture/CMakeLists.txt reads it at build time for the C++ validation)."""
import importlib
import os

_HERE = os.path.dirname(__file__)
LAYOUTS = {
    name[:-3]: importlib.import_module(f"{__name__}.{name[:-3]}").build
    for name in sorted(os.listdir(_HERE))
    if name.endswith(".py") and not name.startswith("_")
}
