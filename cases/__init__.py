"""The case files and study definitions of bubblemesh's validation suite (data, no code).

Installed as ``bubblemesh.studies.data``; see README.md here for the file formats.
"""
