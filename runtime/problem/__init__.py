"""Rod problems as data: the schema and its checks, geometry, sections, materials, ends,
loads and their time functions, the registry of named problems, and their assembly into
a model (``assemble.build_model``)."""
