"""Scenes: the schema (Scene.from_dict, load_scene), the readers of its sections (robot,
contacts, base) and their validation."""
