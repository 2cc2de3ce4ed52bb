from setuptools import setup

PACKAGE = "bearing_recordings"

setup(
    name=PACKAGE,
    version="0.2.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="bearing-monitor maintainers",
    maintainer_email="maintainers@bearing-monitor.invalid",
    description="Vibration recordings (MFPT, CWRU, one-signal .mat; bearing-sim .npz) and rosbag2 reading, "
                "writing, recording and replay (bearing-bag).",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "bearing-bag = bearing_recordings.bag_cli:main",
        ],
    },
)
