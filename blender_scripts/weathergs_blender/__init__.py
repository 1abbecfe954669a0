"""The weathergs scene renderer inside Blender 3.4 (blender_scripts/render_scene.py is the entry point).

Modules: spec (strict reading of the scene spec's parameters), materials, builder (meshes),
layouts/ (one module per scene type; the set of modules IS the list of scene types: capture reads it
at build time), render (lights, cameras, render settings, markers, particles).
"""
