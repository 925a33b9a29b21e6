"""Fixed names and separators shared by the mjcf modules."""

PREFIX_SEPARATOR = "/"
PREFIX_SEPARATOR_ESCAPE = "\\"

# Separates the namespace from the identifier in debug messages.
NAMESPACE_SEPARATOR = "@"

# Attribute names with a special meaning.
BASEPATH = "basepath"
CHILDCLASS = "childclass"
CLASS = "class"
DCLASS = "dclass"
NAME = "name"

# Tags with a special meaning.
ACTUATOR = "actuator"
BODY = "body"
JOINT = "joint"
DEFAULT = "default"
MESH = "mesh"
SITE = "site"
SKIN = "skin"
TENDON = "tendon"
WORLDBODY = "worldbody"
MUJOCO = "mujoco"

# Sections whose unnamed elements (file assets aside, which MuJoCo names after their file)
# are written with their generated name only once something refers to them or asks for
# their name: MuJoCo rejects most of them nameless, and one that nothing uses should fail
# as it would in MuJoCo rather than compile under a name the user never gave.
NAMED_ON_DEMAND_SECTIONS = ("asset", "custom")

# Asset kinds that MuJoCo names after their file (without directory and extension) when
# they have no name, and lets you reference by that name.
ASSETS_NAMED_AFTER_FILE = ("mesh", "texture", "hfield", "skin")

# Namespace under which attachment frames are found by `find`.
ATTACHMENT_FRAME = "attachment_frame"

# Longest file name MuJoCo's virtual file system accepts.
MAX_VFS_FILENAME_LENGTH = 98

# Sections whose attributes are global options: two models can only be combined when they
# agree on every option that both set explicitly.
GLOBAL_OPTION_SECTIONS = ("compiler", "option", "size", "visual")

# Compiler attributes that locate asset files on disk; they only matter while loading a
# model, so they never conflict between models and are not written to generated XML (which
# names every file asset by its virtual file system name).
ASSET_DIRECTORY_ATTRIBUTES = ("meshdir", "texturedir", "assetdir")
