"""The shared core: frames and rigid transforms, SE(2), the arena, how the NAO carries
the bear, chair meshes, and the project's exception hierarchy.

Every other package may import it; it imports none of them (numpy, scipy and trimesh
only). tests/test_architecture.py checks both.
"""
