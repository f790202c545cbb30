"""ament_python package ur_sim_driver: the simulator (ur_sim_driver), the glue planner (ur_glue_planner) and the
ground they share (ur_common)."""
from glob import glob

from setuptools import find_packages, setup

PACKAGE = 'ur_sim_driver'

setup(
    name=PACKAGE,
    version='0.1.0',
    packages=find_packages(include=['ur_sim_driver', 'ur_sim_driver.*', 'ur_glue_planner', 'ur_glue_planner.*',
                                    'ur_common']),
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{PACKAGE}']),
        (f'share/{PACKAGE}', ['package.xml']),
        (f'share/{PACKAGE}/config', glob('config/*.yaml')),
        (f'share/{PACKAGE}/config/ur_types', glob('config/ur_types/*.yaml')),
        (f'share/{PACKAGE}/config/scenes', glob('config/scenes/*.yaml')),
        (f'share/{PACKAGE}/meshes', glob('meshes/*.stl')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ur_sim_driver maintainers',
    maintainer_email='maintainers@ur-sim-driver.invalid',
    description='MuJoCo simulation of Universal Robots arms behind the UR ROS 2 driver interfaces, '
                'and a windshield glue-dispensing planner.',
    license='BSD-3-Clause',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'ur_sim = ur_sim_driver.ros.main:main',
            'ur_glue_planner = ur_glue_planner.parts.command:main',
            'ur_glue_studio = ur_glue_planner.studio.node:main',
        ],
    },
)
