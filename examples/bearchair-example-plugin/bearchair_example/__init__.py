"""An example bearchair plug-in (docs/extending.md walks through it).

- ``leaves.AnnounceSeat``: a new leaf, which says where the bear will face;
- ``trees.create_tree_without_assistance``: the mission without the human assistance,
  announcing the seat before the walk (``bearchair run --tree example-no-assistance``);
- ``skills.POLITE_INSTRUCTIONS``: an override of one skill over the defaults;
- ``backends.make_log_speaker``: a toy robot backend, a speaker that writes a file.
"""
