// Mesh file readers. Both return the mesh in object space and throw SceneError naming the mesh file
// (and the line for text formats) on malformed input.
#pragma once
#include <string>

#include "common/scene/scene_desc.h"

namespace mlt {

// Stanford PLY: ascii, binary_little_endian and binary_big_endian. Vertex properties x,y,z and optionally
// nx,ny,nz and a uv pair named u,v | s,t | texture_u,texture_v | texture_s,texture_t. Faces from the list
// `vertex_indices` (or `vertex_index`); polygons are fan-triangulated. Other elements and properties are
// read and ignored.
MeshDesc readPly(const std::string& path);

// Wavefront OBJ through tinyobjloader (triangulated, materials ignored, every object merged). Normals and
// uvs are kept only when every face corner has them. Mitsuba's flip_tex_coords (default true) maps v to 1 - v.
MeshDesc readObj(const std::string& path, bool flipTexCoords = true);

// Mitsuba's `serialized` format (versions 3 and 4; layout in serialized_reader.cpp): shape `shapeIndex`
// of the file, in object space, with its normals and uvs when present (vertex colours are dropped).
// *faceNormalsHint is set when the record asks for face normals (flag 0x0010). Errors name the file and
// the shape index.
MeshDesc readSerialized(const std::string& path, int shapeIndex, bool* faceNormalsHint = nullptr);

}  // namespace mlt
