"""Meshes built with bmesh in real dimensions (object coordinates are metres)."""
import bmesh
import bpy
from mathutils import Vector

from .spec import SpecError

# ---------------------------------------------------------------------------------------------------
# Geometry: every object gets its own small mesh with its real dimensions (object coordinates are
# meters), built with bmesh, which is far faster than bpy.ops for hundreds of objects.

# Every face is flat-shaded and curved surfaces are tessellated this much more finely instead of
# smooth-shaded: Blender's smooth normals differ in their last float bits from one process to the
# next (so did 2-3 % of a render's pixels), and a benchmark's render must repeat bit for bit
# (docs/scenes.md, "Repeatability").
CURVED_SEGMENT_FACTOR = 2


class Builder:
    def __init__(self, materials, collection):
        self.materials = materials
        self.collection = collection
        self.count = 0

    def _object(self, name, bm, material, location, rotation):
        mesh = bpy.data.meshes.new(name)
        bm.to_mesh(mesh)
        bm.free()
        if material not in self.materials:
            raise SpecError("materials", f"the layout uses material \"{material}\", which the spec lacks")
        mesh.materials.append(self.materials[material])
        obj = bpy.data.objects.new(name, mesh)
        obj.location = location
        obj.rotation_euler = rotation
        self.collection.objects.link(obj)
        self.count += 1
        return obj

    def box(self, material, size, location, rotation=(0, 0, 0), name="box"):
        bm = bmesh.new()
        bmesh.ops.create_cube(bm, size=1.0)
        bmesh.ops.scale(bm, vec=Vector(size), verts=bm.verts)
        return self._object(name, bm, material, location, rotation)

    def cylinder(self, material, radius, depth, location, rotation=(0, 0, 0), segments=16, radius2=None,
                 name="cylinder"):
        bm = bmesh.new()
        bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=segments * CURVED_SEGMENT_FACTOR,
                              radius1=radius, radius2=radius if radius2 is None else radius2, depth=depth)
        return self._object(name, bm, material, location, rotation)

    def sphere(self, material, radius, location, scale=(1, 1, 1), segments=16, name="sphere"):
        bm = bmesh.new()
        segments *= CURVED_SEGMENT_FACTOR
        bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=max(6, segments // 2), radius=radius)
        bmesh.ops.scale(bm, vec=Vector(scale), verts=bm.verts)
        return self._object(name, bm, material, location, (0, 0, 0))
